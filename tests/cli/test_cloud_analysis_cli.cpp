#include <catch2/catch.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>
#include <scene_schema/entities.hpp>
#include "stereoscene/support/angles.hpp"

using stereoscene::support::kPi;

namespace fs = std::filesystem;

namespace {

const fs::path kSample = fs::path(STEREOSCENE_SAMPLES_DIR) / "synthetic";

struct Run {
    int code = -1;
    std::string out;
    std::string err;
};

std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string quote(const std::string& s) { return "'" + s + "'"; }

/// A fresh empty folder for one test, removed when the test ends. The process id keeps runs of
/// the suite from other worktrees on the same machine out of each other's folders.
struct ScratchDir : fs::path {
    explicit ScratchDir(const fs::path& p) : fs::path(p) {
        fs::remove_all(*this);
        fs::create_directories(*this);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    ~ScratchDir() {
        std::error_code ignored;
        fs::remove_all(*this, ignored);
    }
};

ScratchDir scratch(const std::string& name) {
    return ScratchDir(fs::temp_directory_path() /
                      ("stereoscene_cli_" + name + "_" + std::to_string(::getpid())));
}

/// Runs a shell command line with stdout and stderr captured in files of `dir`.
Run run(const std::string& command, const fs::path& dir) {
    const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
    const int status =
        std::system((command + " >" + quote(out.string()) + " 2>" + quote(err.string())).c_str());
    Run r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
}

std::string tool() { return quote(CLOUD_ANALYSIS_EXE); }

/// Flags naming the bundled sample's files; `semantic` and `calib` replace the sample's.
std::string sample_inputs(fs::path semantic = kSample / "semantic.png",
                          fs::path calib = kSample / "calib.yaml") {
    return " --left " + quote((kSample / "left.png").string()) + " --right " +
           quote((kSample / "right.png").string()) + " --semantic " + quote(semantic.string()) +
           " --calib " + quote(calib.string()) + " --frame synthetic-street";
}

std::size_t count_lines(const std::string& text) {
    return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

/// The whitespace-separated numbers of each line of `text`.
std::vector<std::vector<double>> numeric_rows(const std::string& text) {
    std::vector<std::vector<double>> rows;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        std::istringstream cols(line);
        std::vector<double> row;
        for (double v; cols >> v;) row.push_back(v);
        rows.push_back(std::move(row));
    }
    return rows;
}

/// The one file CloudCompare exported into `dir` (it names it after the input and the time).
fs::path only_export(const fs::path& dir, const std::string& ext) {
    fs::path found;
    int n = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        if (e.path().extension() == ext) {
            found = e.path();
            ++n;
        }
    }
    REQUIRE(n == 1);
    return found;
}

}  // namespace

TEST_CASE("cloud-analysis --help exits 0 and lists the flags", "[cli]") {
    const auto dir = scratch("help");
    const Run r = run(tool() + " --help", dir);
    CHECK(r.code == 0);
    for (const char* flag : {"--kitti-root", "--block-size", "--wls", "--xyz", "--pcd", "--ply",
                             "--disparity-kitti", "--timings", "--entities"}) {
        CHECK(r.out.find(flag) != std::string::npos);
    }
    CHECK(r.err.empty());
    const Run v = run(tool() + " --version", dir);
    CHECK(v.code == 0);
    CHECK(v.out.rfind("cloud-analysis ", 0) == 0);
}

TEST_CASE("an unknown flag or a missing required input is a usage error, exit 2", "[cli]") {
    const auto dir = scratch("usage");
    const Run bad = run(tool() + " --no-such-flag", dir);
    CHECK(bad.code == 2);
    CHECK(count_lines(bad.err) == 1);
    CHECK(bad.err.rfind("cloud-analysis: error: ", 0) == 0);
    const Run no_left = run(tool() + " --right x.png --calib c.yaml", dir);
    CHECK(no_left.code == 2);
    const Run bad_value = run(tool() + sample_inputs() + " --block-size 4", dir);
    CHECK(bad_value.code == 2);
    CHECK(bad_value.err.find("--block-size: must be odd") != std::string::npos);
}

TEST_CASE("a missing input file exits 1 naming it and leaves no output file", "[cli]") {
    const auto dir = scratch("missing");
    const fs::path json = dir / "e.json", ply = dir / "c.ply";
    const Run r = run(tool() + " --left " + quote((dir / "nope.png").string()) + " --right " +
                          quote((kSample / "right.png").string()) + " --calib " +
                          quote((kSample / "calib.yaml").string()) + " -o " + quote(json.string()) +
                          " --ply " + quote(ply.string()),
                      dir);
    CHECK(r.code == 1);
    CHECK(count_lines(r.err) == 1);
    CHECK(r.err.find("nope.png") != std::string::npos);
    CHECK_FALSE(fs::exists(json));
    CHECK_FALSE(fs::exists(ply));
}

TEST_CASE("an output into a missing folder fails before any work and writes nothing", "[cli]") {
    const auto dir = scratch("no_folder");
    const fs::path json = dir / "e.json";
    const Run r = run(tool() + sample_inputs() + " -o " + quote(json.string()) + " --ply " +
                          quote((dir / "missing" / "c.ply").string()),
                      dir);
    CHECK(r.code == 1);
    CHECK(r.err.find("no such folder") != std::string::npos);
    CHECK(r.err.find("--ply") != std::string::npos);
    CHECK_FALSE(fs::exists(json));
    const Run two = run(tool() + sample_inputs() + " -o - --disparity-kitti -", dir);
    CHECK(two.code == 2);
    const Run las =
        run(tool() + sample_inputs() + " --xyz " + quote((dir / "c.las").string()), dir);
    CHECK(las.code == 2);
    CHECK(las.err.find(".las") != std::string::npos);
}

TEST_CASE("a semantic image of another size and a zero baseline fail before any output", "[cli]") {
    const auto dir = scratch("mismatch");
    const Run small = run(
        tool() + " make-sample --width 320 --height 100 --out " + quote((dir / "small").string()),
        dir);
    REQUIRE(small.code == 0);
    const fs::path json = dir / "e.json";
    const Run r =
        run(tool() + sample_inputs(dir / "small" / "semantic.png") + " -o " + quote(json.string()),
            dir);
    CHECK(r.code == 1);
    CHECK(r.err.find("semantic image is 320x100") != std::string::npos);
    CHECK_FALSE(fs::exists(json));

    std::ofstream(dir / "zero.yaml") << "fx: 360\nfy: 360\ncx: 310\ncy: 86\nbaseline_m: 0\n";
    const Run z = run(tool() + sample_inputs(kSample / "semantic.png", dir / "zero.yaml") + " -o " +
                          quote(json.string()),
                      dir);
    CHECK(z.code == 1);
    CHECK(z.err.find("baseline_m: must be > 0") != std::string::npos);
    CHECK(z.err.find("zero.yaml") != std::string::npos);
    CHECK_FALSE(fs::exists(json));
}

TEST_CASE("a disparity offset brings every car nearer and is recorded, a wild one is refused",
          "[cli]") {
    const auto dir = scratch("disparity_offset");
    const fs::path plain = dir / "plain.json", shifted = dir / "shifted.json";
    REQUIRE(run(tool() + sample_inputs() + " -o " + quote(plain.string()), dir).code == 0);
    REQUIRE(
        run(tool() + sample_inputs() + " --disparity-offset 0.5 -o " + quote(shifted.string()), dir)
            .code == 0);
    const auto nearest_car_z = [](const nlohmann::json& doc) {
        double z = 1e9;
        for (const auto& e : doc["entities"]) {
            if (e["class"] == "car") z = std::min(z, e["z"].get<double>());
        }
        return z;
    };
    const auto a = nlohmann::json::parse(slurp(plain));
    const auto b = nlohmann::json::parse(slurp(shifted));
    CHECK(a["source"]["calibration"]["disparity_offset_px"] == 0.0);
    CHECK(b["source"]["calibration"]["disparity_offset_px"] == 0.5);
    REQUIRE(nearest_car_z(a) < 1e9);
    CHECK(nearest_car_z(b) < nearest_car_z(a) - 0.05);

    const fs::path wild = dir / "wild.json";
    const Run r =
        run(tool() + sample_inputs() + " --disparity-offset 9 -o " + quote(wild.string()), dir);
    CHECK(r.code == 2);
    CHECK(r.err.find("--disparity-offset") != std::string::npos);
    CHECK(count_lines(r.err) == 1);
    CHECK_FALSE(fs::exists(wild));
}

TEST_CASE("make-sample reproduces the bundled synthetic sample byte for byte", "[cli][synthetic]") {
    const auto dir = scratch("make_sample");
    const Run r = run(tool() + " make-sample --out " + quote(dir.string()), dir);
    REQUIRE(r.code == 0);
    for (const char* f : {"left.png", "right.png", "semantic.png", "disparity_gt.png", "calib.yaml",
                          "truth.json"}) {
        INFO(f);
        CHECK(slurp(dir / f) == slurp(kSample / f));
    }
}

TEST_CASE("the synthetic sample's entities lie close to its ground truth", "[cli][synthetic]") {
    const auto dir = scratch("sample_entities");
    const Run r = run(tool() + sample_inputs() + " -o -", dir);
    REQUIRE(r.code == 0);
    const scene_schema::EntityDocument got = scene_schema::parse(r.out);
    const scene_schema::EntityDocument truth = scene_schema::read_file(kSample / "truth.json");
    CHECK(got.frame.id == "synthetic-street");
    REQUIRE(got.source.has_value());
    CHECK((*got.source)["tool"] == "cloud-analysis");
    CHECK((*got.source)["disparity"]["block_size"].is_number());
    int cars = 0;
    for (const auto& t : truth.entities) {
        if (t.class_name != "car" && t.class_name != "person") continue;
        // The far car shows only its back: its heading (and so its centre) is ambiguous.
        const double tolerance = t.z > 20.0 ? 2.5 : 0.5;
        const scene_schema::Entity* best = nullptr;
        double best_d = 1e9;
        for (const auto& e : got.entities) {
            if (e.class_name != t.class_name) continue;
            const double d = std::hypot(e.x - t.x, e.z - t.z);
            if (d < best_d) {
                best_d = d;
                best = &e;
            }
        }
        INFO(t.id << " at x " << t.x << " z " << t.z);
        REQUIRE(best != nullptr);
        CHECK(best_d < tolerance);
        CHECK(std::abs(best->y - t.y) < 0.2);
        if (t.class_name == "car" && t.z < 20.0) {
            ++cars;
            const double dtheta = std::remainder(best->theta - t.theta, kPi);
            CHECK(std::abs(dtheta) < 0.25);
            CHECK(best->L == Approx(t.L).margin(0.6));
            CHECK(best->W == Approx(t.W).margin(0.6));
        }
    }
    CHECK(cars == 2);
    const auto& plane = got.extra.at("ground_plane");
    CHECK(plane.at("camera_height_m").get<double>() == Approx(1.65).margin(0.05));
}

TEST_CASE("CloudCompare loads our .xyz and .ply with every point and PCL reads our .pcd",
          "[cli][cloud_io]") {
    const auto dir = scratch("clients");
    const Run r =
        run(tool() + sample_inputs() + " --xyz " + quote((dir / "c.xyz").string()) + " --ply " +
                quote((dir / "c.ply").string()) + " --pcd " + quote((dir / "c.pcd").string()),
            dir);
    REQUIRE(r.code == 0);
    const std::string xyz = slurp(dir / "c.xyz");
    REQUIRE(xyz.rfind("//X Y Z R G B Class Luma\n", 0) == 0);
    const std::size_t points = count_lines(xyz) - 1;
    REQUIRE(points > 10000);
    // The clouds are written atomically but not fsync'ed unless asked: the same bytes either way.
    REQUIRE(run(tool() + sample_inputs() + " --fsync-clouds --xyz " +
                    quote((dir / "durable.xyz").string()),
                dir)
                .code == 0);
    CHECK(slurp(dir / "durable.xyz") == xyz);

    // Every column survives CloudCompare with its values: x y z r g b class luma from the .xyz
    // (8 columns), x y z r g b class from the .ply (7), point for point.
    const std::vector<std::vector<double>> ours = numeric_rows(xyz.substr(xyz.find('\n') + 1));
    REQUIRE(ours.size() == points);
    for (const auto& [name, columns] : {std::pair<const char*, std::size_t>{"c.xyz", 8},
                                        std::pair<const char*, std::size_t>{"c.ply", 7}}) {
        INFO(name);
        const auto sub = scratch(std::string("clients_") + name);
        fs::copy_file(dir / name, sub / name);
        const Run cc = run("QT_QPA_PLATFORM=offscreen " + quote(CLOUDCOMPARE_EXE) + " -SILENT -O " +
                               quote((sub / name).string()) + " -C_EXPORT_FMT ASC -SAVE_CLOUDS",
                           sub);
        REQUIRE(cc.code == 0);
        const auto exported = numeric_rows(slurp(only_export(sub, ".asc")));
        REQUIRE(exported.size() == points);
        std::size_t mismatches = 0;
        for (std::size_t i = 0; i < points; ++i) {
            REQUIRE(exported[i].size() == columns);
            for (std::size_t c = 0; c < columns; ++c) {
                // CloudCompare stores coordinates as floats: within a millimetre of our text.
                const double tolerance = c < 3 ? 1e-3 : 0.0;
                if (std::abs(exported[i][c] - ours[i][c]) > tolerance) ++mismatches;
            }
        }
        CHECK(mismatches == 0);
    }

    const Run pcl = run(quote(PCL_CONVERT_EXE) + " " + quote((dir / "c.pcd").string()) + " " +
                            quote((dir / "ascii.pcd").string()) + " 0",
                        dir);
    REQUIRE(pcl.code == 0);
    const std::string ascii = slurp(dir / "ascii.pcd");
    CHECK(ascii.find("FIELDS x y z rgb label") != std::string::npos);
    CHECK(ascii.find("POINTS " + std::to_string(points) + "\n") != std::string::npos);
    const auto data = ascii.find("DATA ascii\n");
    REQUIRE(data != std::string::npos);
    CHECK(count_lines(ascii.substr(data)) - 1 == points);
}

namespace {

/// A KITTI-layout folder holding the bundled sample as frame `street_10`.
fs::path sample_as_kitti(const fs::path& dir) {
    const fs::path root = dir / "kitti";
    for (const auto& [sub, name, ext] :
         {std::tuple<const char*, const char*, const char*>{"image_2", "left.png", ".png"},
          {"image_3", "right.png", ".png"},
          {"semantic_rgb", "semantic.png", ".png"},
          {"calib", "calib.yaml", ".txt"}}) {
        fs::create_directories(root / sub);
        fs::copy_file(kSample / name, root / sub / (std::string("street_10") + ext));
    }
    return root;
}

}  // namespace

TEST_CASE("batch writes what analyse writes per frame and names a failed frame, exit 1",
          "[cli][batch]") {
    const auto dir = scratch("batch");
    const fs::path root = sample_as_kitti(dir);
    const fs::path out = dir / "out";
    fs::create_directories(out);
    const Run r = run(tool() + " batch --kitti-root " + quote(root.string()) +
                          " --frames street_10 missing_10 street_10 --clouds ply --out-dir " +
                          quote(out.string()) + " --report " + quote((dir / "r.json").string()),
                      dir);
    CHECK(r.code == 1);
    CHECK(r.err.find("error: frame missing_10:") != std::string::npos);
    CHECK(r.err.find("3/3 frames") != std::string::npos);
    CHECK(fs::exists(out / "street_10.ply"));
    CHECK_FALSE(fs::exists(out / "missing_10.json"));
    const auto report = nlohmann::json::parse(slurp(dir / "r.json"));
    CHECK(report["frames"] == 3);
    CHECK(report["failed"] == 1);
    CHECK(report["per_frame"].size() == 3);
    CHECK(report["per_frame"][2]["points"].get<std::size_t>() > 50000);
    // The CPU figures and the main thread's waits, which the machine's load does not hide.
    CHECK(report["cpu_ms_per_frame"].get<double>() > 1.0);
    CHECK(report["cores_busy"].get<double>() > 0.0);
    CHECK(report["cores_busy"].get<double>() <= 1.05);
    for (const auto& frame : report["per_frame"]) {
        CHECK(frame["wait_load_ms"].get<double>() >= 0.0);
        CHECK(frame["wait_finish_ms"].get<double>() >= 0.0);
    }
    CHECK(r.err.find("ms CPU per frame, cores") != std::string::npos);

    // The same frame through `analyse` gives the same entity file, byte for byte.
    const Run one = run(tool() + " --kitti-root " + quote(root.string()) +
                            " --frame street_10 -o " + quote((dir / "one.json").string()),
                        dir);
    REQUIRE(one.code == 0);
    CHECK(slurp(out / "street_10.json") == slurp(dir / "one.json"));
    const scene_schema::EntityDocument doc = scene_schema::read_file(out / "street_10.json");
    CHECK(doc.frame.id == "street_10");
    CHECK_FALSE(doc.entities.empty());
}

TEST_CASE("batch without frames or with both --frames and --list is a usage error",
          "[cli][batch]") {
    const auto dir = scratch("batch_usage");
    const std::string base =
        tool() + " batch --kitti-root " + quote(dir.string()) + " --out-dir " + quote(dir.string());
    CHECK(run(base, dir).code == 2);
    std::ofstream(dir / "list.txt") << "# frames\nstreet_10\n";
    CHECK(run(base + " --frames a --list " + quote((dir / "list.txt").string()), dir).code == 2);
    CHECK(run(base + " --frames a --preset turbo", dir).code == 2);
}

namespace {

/// The sample as three KITTI frames a_10 b_10 c_10 (same images, different ids).
fs::path three_frames(const fs::path& dir) {
    const fs::path root = sample_as_kitti(dir);
    for (const char* sub : {"image_2", "image_3", "semantic_rgb", "calib"}) {
        const std::string ext = std::string(sub) == "calib" ? ".txt" : ".png";
        for (const char* id : {"a_10", "b_10", "c_10"}) {
            fs::copy_file(root / sub / ("street_10" + ext), root / sub / (id + ext));
        }
    }
    return root;
}

std::string batch_of_three(const fs::path& root, const fs::path& out) {
    fs::create_directories(out);
    return tool() + " batch --kitti-root " + quote(root.string()) +
           " --frames a_10 b_10 c_10 --preset fast --out-dir " + quote(out.string());
}

}  // namespace

TEST_CASE("two shards do what one process does, and report merges their reports",
          "[cli][batch][shard]") {
    const auto dir = scratch("batch_shards");
    const fs::path root = three_frames(dir);
    REQUIRE(run(batch_of_three(root, dir / "one") + " --quiet", dir).code == 0);
    const std::string sharded = batch_of_three(root, dir / "two");
    const Run first =
        run(sharded + " --shard 0/2 --report " + quote((dir / "r0.json").string()), dir);
    REQUIRE(first.code == 0);
    CHECK(first.err.find("2 of 3 frames in this share") != std::string::npos);
    CHECK_FALSE(fs::exists(dir / "two" / "b_10.json"));
    // Shard 1/2 from a Slurm array task's variables.
    const Run second = run("SLURM_ARRAY_TASK_ID=1 SLURM_ARRAY_TASK_COUNT=2 " + sharded +
                               " --report " + quote((dir / "r1.json").string()),
                           dir);
    REQUIRE(second.code == 0);
    for (const char* frame : {"a_10", "b_10", "c_10"}) {
        CAPTURE(frame);
        CHECK(slurp(dir / "two" / (std::string(frame) + ".json")) ==
              slurp(dir / "one" / (std::string(frame) + ".json")));
    }
    const Run merged = run(tool() + " report " + quote((dir / "r0.json").string()) + " " +
                               quote((dir / "r1.json").string()),
                           dir);
    REQUIRE(merged.code == 0);
    const auto report = nlohmann::json::parse(merged.out);
    CHECK(report["frames"] == 3);
    CHECK(report["done"] == 3);
    CHECK(report["shards_reported"] == 2);
    CHECK(report["fps"].get<double>() > 0.0);
    // A missing shard: the report is written, the shard named, exit 1.
    const Run missing = run(tool() + " report --shards 2 -o " + quote((dir / "m.json").string()) +
                                " " + quote((dir / "r1.json").string()),
                            dir);
    CHECK(missing.code == 1);
    CHECK(missing.err.find("shard 0/2: no report") != std::string::npos);
    CHECK(fs::exists(dir / "m.json"));
    CHECK(run(sharded + " --shard 2/2", dir).code == 2);
    CHECK(run("SLURM_ARRAY_TASK_ID=3 SLURM_ARRAY_TASK_COUNT=2 " + sharded, dir).code == 2);
    CHECK(run(tool() + " report " + quote((dir / "nope.json").string()), dir).code == 1);
}

TEST_CASE("a resumed batch keeps finished frames untouched and redoes broken or missing ones",
          "[cli][batch][resume]") {
    const auto dir = scratch("batch_resume");
    const fs::path root = three_frames(dir);
    const fs::path out = dir / "out";
    const std::string batch = batch_of_three(root, out) + " --clouds pcd";
    REQUIRE(run(batch + " --quiet", dir).code == 0);
    const std::string reference = slurp(out / "b_10.json");
    const auto a_time = fs::last_write_time(out / "a_10.json");
    // b_10's entity file cut short, c_10's cloud gone, a killed writer's temporary left.
    fs::resize_file(out / "b_10.json", fs::file_size(out / "b_10.json") / 2);
    fs::remove(out / "c_10.pcd");
    std::ofstream(out / ".c_10.json.tmp-AbCdEf") << "{";
    const Run r = run(batch + " --resume --report " + quote((dir / "r.json").string()), dir);
    REQUIRE(r.code == 0);
    CHECK(r.err.find("1 already done, 2 to do") != std::string::npos);
    CHECK(fs::last_write_time(out / "a_10.json") == a_time);
    CHECK(slurp(out / "b_10.json") == reference);
    CHECK(fs::exists(out / "c_10.pcd"));
    CHECK_FALSE(fs::exists(out / ".c_10.json.tmp-AbCdEf"));
    const auto report = nlohmann::json::parse(slurp(dir / "r.json"));
    CHECK(report["skipped"] == 1);
    CHECK(report["done"] == 2);
    CHECK(report["frames"] == 3);
    // Everything done: nothing is rewritten, and --quiet prints nothing.
    const Run again = run(batch + " --resume --quiet", dir);
    CHECK(again.code == 0);
    CHECK(again.err.empty());
    CHECK(fs::last_write_time(out / "a_10.json") == a_time);
}

TEST_CASE("bench reports frames from memory and from files beside the matcher alone as JSON",
          "[cli][bench]") {
    const auto dir = scratch("bench");
    const Run r = run(tool() + " bench" + sample_inputs() + " --runs 1 --warmup 0 --work-dir " +
                          quote(dir.string()),
                      dir);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    const double matcher = j["matcher_ms"];
    CHECK(matcher > 0.0);
    CHECK(j["inputs"]["memory"].get<std::string>().find("camera") != std::string::npos);
    CHECK(j["inputs"]["files"].get<std::string>().find("decode") != std::string::npos);
    REQUIRE(j["rows"].size() == 4);
    const auto stage_names = [](const nlohmann::json& row) {
        std::vector<std::string> names;
        for (const auto& s : row["stages"]) names.push_back(s["stage"]);
        return names;
    };
    for (const auto& row : j["rows"]) {
        const double total = row["total_ms"];
        CHECK(row["ratio_to_matcher"].get<double>() == Approx(total / matcher));
        const auto names = stage_names(row);
        // From memory the frame is decoded already: the first stage is the matcher's; from
        // files the load (PNG decode) comes first.
        const bool from_files = row["input"] == "files";
        REQUIRE(names.size() >= 2);
        CHECK(names[0] == (from_files ? "load" : "disparity"));
        CHECK(names[from_files ? 1 : 0] == "disparity");
        CHECK(std::count(names.begin(), names.end(), "write --entities") == 1);
    }
    CHECK(j["rows"][0]["input"] == "memory");
    CHECK(j["rows"][2]["input"] == "files");
    CHECK(stage_names(j["rows"][1]).size() > stage_names(j["rows"][0]).size());
    CHECK(stage_names(j["rows"][3]).size() > stage_names(j["rows"][2]).size());
    CHECK(j["peak_rss_mb"].get<double>() > 10.0);
    CHECK(fs::exists(dir / "bench.ply"));
}

TEST_CASE("bench times the odometry's cost per frame when given the next frame's left image",
          "[cli][bench][odometry]") {
    const auto dir = scratch("bench_odometry");
    const std::string bench = tool() + " bench" + sample_inputs() +
                              " --runs 1 --warmup 0 --work-dir " + quote(dir.string());
    const Run r = run(bench + " --next-left " + quote((kSample / "right.png").string()), dir);
    REQUIRE(r.code == 0);
    const auto j = nlohmann::json::parse(r.out);
    CHECK(j["odometry_ms"].get<double>() > 0.0);
    CHECK(j["odometry_cpu_ms"].get<double>() >= 0.0);
    // Without it, no odometry entry.
    const Run plain = run(bench, dir);
    REQUIRE(plain.code == 0);
    CHECK(nlohmann::json::parse(plain.out).count("odometry_ms") == 0);
    // A next frame of another size is an error naming the flag.
    const fs::path other =
        fs::path(STEREOSCENE_SAMPLES_DIR) / "rendered/kerbside-1/image_2/000000.png";
    const Run bad = run(bench + " --next-left " + quote(other.string()), dir);
    CHECK(bad.code == 1);
    CHECK(bad.err.find("--next-left") != std::string::npos);
    CHECK(std::count(bad.err.begin(), bad.err.end(), '\n') == 1);
    // With the frame before, the timed frame's tracks start from the drive's motion.
    const std::string left = quote((kSample / "left.png").string());
    const std::string right = quote((kSample / "right.png").string());
    const Run primed = run(
        bench + " --next-left " + left + " --prev-left " + left + " --prev-right " + right, dir);
    REQUIRE(primed.code == 0);
    CHECK(nlohmann::json::parse(primed.out)["odometry_ms"].get<double>() > 0.0);
    for (const std::string& flags :
         {" --next-left " + left + " --prev-left " + left,
          std::string(" --prev-left ") + left + " --prev-right " + right,
          " --next-left " + left + " --prev-left " + quote(other.string()) + " --prev-right " +
              quote(other.string())}) {
        const Run wrong = run(bench + flags, dir);
        CHECK(wrong.code == 1);
        CHECK(wrong.err.find("--prev-") != std::string::npos);
        CHECK(std::count(wrong.err.begin(), wrong.err.end(), '\n') == 1);
    }
}

TEST_CASE("the palette flag takes a palette file path as well as a bundled name",
          "[cli][semantic]") {
    const auto dir = scratch("palette_path");
    const fs::path file = fs::path(STEREOSCENE_SOURCE_DIR) / "assets/palettes/cityscapes.json";
    const Run by_name = run(tool() + sample_inputs() + " --palette cityscapes -o -", dir);
    const Run by_path =
        run(tool() + sample_inputs() + " --palette " + quote(file.string()) + " -o -", dir);
    REQUIRE(by_name.code == 0);
    REQUIRE(by_path.code == 0);
    CHECK(by_path.out == by_name.out);
    const Run missing = run(
        tool() + sample_inputs() + " --palette " + quote((dir / "none.json").string()) + " -o -",
        dir);
    CHECK(missing.code == 1);
    CHECK(missing.err.find("none.json") != std::string::npos);
}

namespace {

const fs::path kStreet = fs::path(STEREOSCENE_SAMPLES_DIR) / "rendered" / "street";

/// The rendered street's pair and calibration, without its semantic image.
std::string street_pair(const fs::path& calib = kStreet / "calib" / "calib_cam_to_cam.txt") {
    return " --left " + quote((kStreet / "image_2" / "000000.png").string()) + " --right " +
           quote((kStreet / "image_3" / "000000.png").string()) + " --calib " +
           quote(calib.string()) + " --frame 000000";
}

}  // namespace

TEST_CASE("without a semantic image the stereo pair alone gives cars, and the file says so",
          "[cli][geometry]") {
    const auto dir = scratch("stereo_only");
    const fs::path semantic = dir / "derived.png";
    const Run r =
        run(tool() + street_pair() + " -o - --semantic-out " + quote(semantic.string()), dir);
    REQUIRE(r.code == 0);
    CHECK(r.err.find("every point is void") == std::string::npos);
    const auto doc = nlohmann::json::parse(r.out);
    CHECK(doc["source"]["semantics"] == "geometry");
    CHECK(doc["stereo_ground"]["camera_height_m"].get<double>() == Approx(1.65).margin(0.1));
    int cars = 0;
    for (const auto& e : doc["entities"]) {
        if (e["class"] != "car") continue;
        ++cars;
        CHECK(e["confidence"].get<double>() <= 0.6);  // geometry's classes: less confidence
    }
    CHECK(cars >= 5);
    CHECK(fs::file_size(semantic) > 1000);

    // Asked for, the labelled path says "labels" and leaves confidence as it was.
    const Run labelled =
        run(tool() + street_pair() + " --semantic " +
                quote((kStreet / "semantic_rgb" / "000000.png").string()) + " -o -",
            dir);
    REQUIRE(labelled.code == 0);
    CHECK(nlohmann::json::parse(labelled.out)["source"]["semantics"] == "labels");
    const Run forced = run(tool() + street_pair() + " --semantic " +
                               quote((kStreet / "semantic_rgb" / "000000.png").string()) +
                               " --semantics geometry -o -",
                           dir);
    REQUIRE(forced.code == 0);
    CHECK(nlohmann::json::parse(forced.out)["source"]["semantics"] == "geometry");
    CHECK(run(tool() + street_pair() + " --semantics colour -o -", dir).code == 2);
}

TEST_CASE("the stereo-only segments are written as a table and an id image, or not at all",
          "[cli][geometry]") {
    const auto dir = scratch("segments_out");
    const fs::path table = dir / "segments.json", ids = dir / "segments.png",
                   out = dir / "entities.json";
    const Run r = run(tool() + street_pair() + " -o " + quote(out.string()) + " --segments-out " +
                          quote(table.string()) + " --segment-ids-out " + quote(ids.string()),
                      dir);
    REQUIRE(r.code == 0);
    const auto doc = nlohmann::json::parse(slurp(table));
    CHECK(doc["frame"] == "000000");
    int cars = 0;
    for (const auto& s : doc["segments"]) {
        if (s["class"] == "car") ++cars;
        CHECK(s["box_px"][0].get<int>() <= s["box_px"][2].get<int>());
    }
    CHECK(cars >= 3);
    // A 16-bit grey PNG of the left image's size (its IHDR: width, height, depth, colour type).
    const std::string png = slurp(ids);
    REQUIRE(png.size() > 26);
    const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(png[k]); };
    CHECK(png.compare(1, 3, "PNG") == 0);
    CHECK((byte(18) << 8 | byte(19)) == 1242);
    CHECK((byte(22) << 8 | byte(23)) == 375);
    CHECK(byte(24) == 16);
    CHECK(byte(25) == 0);
    // The labelled path has no segments: an error naming the flag, and no file at all.
    fs::remove(table);
    fs::remove(out);
    const Run labelled =
        run(tool() + street_pair() + " --semantic " +
                quote((kStreet / "semantic_rgb" / "000000.png").string()) + " -o " +
                quote(out.string()) + " --segments-out " + quote(table.string()),
            dir);
    CHECK(labelled.code == 1);
    CHECK(labelled.err.find("--segments-out") != std::string::npos);
    CHECK_FALSE(fs::exists(table));
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("the classifiers' votes are in the segments table, a bad classifier is refused",
          "[cli][geometry]") {
    const auto dir = scratch("vehicle_classifier");
    const fs::path table = dir / "segments.json", out = dir / "entities.json";
    const Run r = run(tool() + street_pair() + " -o " + quote(out.string()) + " --segments-out " +
                          quote(table.string()),
                      dir);
    REQUIRE(r.code == 0);
    for (const auto& s : nlohmann::json::parse(slurp(table))["segments"]) {
        REQUIRE(s["vehicle_votes"].is_number());
        CHECK(s["features"].size() == 25);
        // A car is what a majority of the trees call a vehicle, whatever the rules said; a person
        // what is no car and a majority of the person trees call one.
        const bool car = s["vehicle_votes"].get<double>() > 0.5;
        CHECK((s["class"] == "car") == car);
        CHECK(s["person_votes"].is_null() == car);
        if (!car) CHECK((s["class"] == "person") == (s["person_votes"].get<double>() > 0.5));
    }
    // The rules alone: no votes.
    const Run rules = run(tool() + street_pair() +
                              " -o - --vehicle-classifier none --person-classifier none "
                              "--segments-out " +
                              quote(table.string()),
                          dir);
    REQUIRE(rules.code == 0);
    for (const auto& s : nlohmann::json::parse(slurp(table))["segments"]) {
        CHECK(s["vehicle_votes"].is_null());
        CHECK(s["person_votes"].is_null());
        CHECK(s["class"] == s["rules_class"]);
    }
    // A vehicle classifier given as the person classifier: refused by its format.
    fs::remove(out);
    const fs::path vehicle_trees =
        fs::path(STEREOSCENE_SOURCE_DIR) / "assets/classifiers/vehicle-segments.json";
    const Run swapped = run(tool() + street_pair() + " -o " + quote(out.string()) +
                                " --person-classifier " + quote(vehicle_trees.string()),
                            dir);
    CHECK(swapped.code == 2);
    CHECK(swapped.err.find("--person-classifier") != std::string::npos);
    CHECK(swapped.err.find("stereoscene-person-classifier") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
    // A classifier that is not there: a usage error naming the flag and the file, nothing written.
    const Run bad = run(tool() + street_pair() + " -o " + quote(out.string()) +
                            " --vehicle-classifier " + quote((dir / "none.json").string()),
                        dir);
    CHECK(bad.code == 2);
    CHECK(bad.err.find("--vehicle-classifier") != std::string::npos);
    CHECK(bad.err.find("none.json") != std::string::npos);
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("a calibration whose baseline puts the road 10 m down warns, writes, and finds no car",
          "[cli][geometry]") {
    const auto dir = scratch("stereo_only_bad");
    // The street's rig with six times its baseline: every depth six times too far.
    std::ofstream(dir / "calib.yaml") << "fx: 721.5377\nfy: 721.5377\ncx: 609.5593\n"
                                         "cy: 172.854\nbaseline_m: 3.24\n";
    const fs::path out = dir / "entities.json";
    const Run r = run(tool() + street_pair(dir / "calib.yaml") + " -o " + quote(out.string()), dir);
    REQUIRE(r.code == 0);
    CHECK(r.err.find("warning: no ground found: the fitted road lies") != std::string::npos);
    CHECK(r.err.find("baseline") != std::string::npos);
    REQUIRE(fs::exists(out));
    const auto doc = nlohmann::json::parse(slurp(out));
    CHECK(doc["stereo_ground"]["found"] == false);
    for (const auto& e : doc["entities"]) CHECK(e["class"] != "car");
}

TEST_CASE("export-kitti writes camera 0 locations and evaluate --labels reads them back",
          "[cli][kitti_labels]") {
    const auto dir = scratch("export_kitti_frame");
    // A KITTI object calibration: camera 2 sits (44.85728 - 609.5593 * 0.002745884) / 721.5377
    // = 0.05985 m right of camera 0.
    std::ofstream(dir / "calib.txt")
        << "P0: 721.5377 0 609.5593 0 0 721.5377 172.854 0 0 0 1 0\n"
           "P1: 721.5377 0 609.5593 -387.5744 0 721.5377 172.854 0 0 0 1 0\n"
           "P2: 721.5377 0 609.5593 44.85728 0 721.5377 172.854 0.2163791 0 0 1 0.002745884\n"
           "P3: 721.5377 0 609.5593 -339.5242 0 721.5377 172.854 2.199936 0 0 1 0.002729905\n";
    const fs::path truth = kSample / "truth.json";
    const Run own = run(tool() + " export-kitti " + quote(truth.string()) + " -o -", dir);
    REQUIRE(own.code == 0);
    CHECK(own.err.find("give --calib") != std::string::npos);  // the truth file does not say
    const fs::path labels = dir / "label_2.txt";
    const Run moved = run(tool() + " export-kitti " + quote(truth.string()) + " --calib " +
                              quote((dir / "calib.txt").string()) + " -o " + quote(labels.string()),
                          dir);
    REQUIRE(moved.code == 0);
    CHECK(moved.err.empty());
    // Every x moved by -0.05985 m (two decimals in the file), y and z by less than 5 mm.
    std::istringstream a(own.out), b(slurp(labels));
    std::string la, lb;
    int lines = 0;
    while (std::getline(a, la) && std::getline(b, lb)) {
        std::istringstream fa(la), fb(lb);
        std::vector<double> va, vb;
        std::string type;
        fa >> type;
        fb >> type;
        for (double v; fa >> v;) va.push_back(v);
        for (double v; fb >> v;) vb.push_back(v);
        REQUIRE(va.size() == vb.size());
        CHECK(vb[10] - va[10] == Approx(-0.05985).margin(0.0051));
        CHECK(std::abs(vb[11] - va[11]) <= 0.0051);
        CHECK(std::abs(vb[12] - va[12]) <= 0.0051);
        ++lines;
    }
    CHECK(lines >= 3);
    // Read back with the same calibration, the labels are the truth again.
    const Run back =
        run(tool() + " evaluate --entities " + quote(truth.string()) + " --labels " +
                quote(labels.string()) + " --calib " + quote((dir / "calib.txt").string()) +
                " --bar-range 50 --require-recall 1.0 --max-spurious 0"
                " --max-median-centre-error 0.01",
            dir);
    CHECK(back.code == 0);
}

TEST_CASE("the sky left out of the clouds (--drop-sky) is not left out of the entities", "[cli]") {
    const auto dir = scratch("drop_sky");
    const std::string street = tool() + street_pair() + " --semantic " +
                               quote((kStreet / "semantic_rgb" / "000000.png").string());
    const Run all = run(street + " --xyz " + quote((dir / "all.xyz").string()) + " -o " +
                            quote((dir / "all.json").string()),
                        dir);
    REQUIRE(all.code == 0);
    const Run dropped = run(street + " --drop-sky --xyz " + quote((dir / "no_sky.xyz").string()) +
                                " -o " + quote((dir / "no_sky.json").string()),
                            dir);
    REQUIRE(dropped.code == 0);
    // Class 23 is the Cityscapes sky: the column after R G B.
    const auto sky_points = [](const fs::path& xyz) {
        std::ifstream in(xyz);
        std::string line;
        std::size_t n = 0, sky = 0;
        std::getline(in, line);  // header
        while (std::getline(in, line)) {
            std::istringstream f(line);
            double x, y, z, r, g, b;
            int cls;
            f >> x >> y >> z >> r >> g >> b >> cls;
            ++n;
            sky += cls == 23;
        }
        return std::make_pair(n, sky);
    };
    const auto [n_all, sky_all] = sky_points(dir / "all.xyz");
    const auto [n_kept, sky_kept] = sky_points(dir / "no_sky.xyz");
    CHECK(sky_all > 0);
    CHECK(sky_kept == 0);
    CHECK(n_kept == n_all - sky_all);
    CHECK(slurp(dir / "all.json") == slurp(dir / "no_sky.json"));
    const Run bad =
        run(street + " --drop-classes skyy --xyz " + quote((dir / "bad.xyz").string()), dir);
    CHECK(bad.code == 2);
    CHECK(bad.err.find("--drop-classes") != std::string::npos);
    CHECK(bad.err.find("skyy") != std::string::npos);
    CHECK_FALSE(fs::exists(dir / "bad.xyz"));
}

TEST_CASE("batch creates its output folder and reports the frames that warned", "[cli][batch]") {
    const auto dir = scratch("batch_warnings");
    const fs::path root = sample_as_kitti(dir);
    // A second frame without a semantic image, and classes from labels only: analysed, every
    // point void, and it says so (with the default --semantics auto it would take the
    // stereo-only path).
    for (const char* sub : {"image_2", "image_3", "calib"}) {
        const std::string ext = std::string(sub) == "calib" ? ".txt" : ".png";
        fs::copy_file(root / sub / ("street_10" + ext), root / sub / ("bare_10" + ext));
    }
    const fs::path out = dir / "new" / "out";  // neither folder exists yet
    const Run r = run(tool() + " batch --kitti-root " + quote(root.string()) +
                          " --frames street_10 bare_10 --semantics labels --out-dir " +
                          quote(out.string()) + " --report " + quote((dir / "r.json").string()),
                      dir);
    REQUIRE(r.code == 0);
    CHECK(fs::exists(out / "street_10.json"));
    CHECK(fs::exists(out / "bare_10.json"));
    CHECK(r.err.find("1 of 2 frames warned, first frame bare_10: no semantic image") !=
          std::string::npos);
    const auto report = nlohmann::json::parse(slurp(dir / "r.json"));
    CHECK(report["frames_with_warnings"] == 1);
    CHECK_FALSE(report["per_frame"][0].contains("warnings"));
    REQUIRE(report["per_frame"][1].contains("warnings"));
    CHECK(report["per_frame"][1]["warnings"][0] == "no semantic image: every point is void");
    // A refused batch creates nothing.
    const fs::path never = dir / "never";
    const Run refused = run(tool() + " batch --kitti-root " + quote((dir / "nope").string()) +
                                " --frames a --out-dir " + quote(never.string()),
                            dir);
    CHECK(refused.code == 1);
    CHECK_FALSE(fs::exists(never));
}

TEST_CASE("track's benchmark follows 50 cars without losing one and says how long it took",
          "[cli]") {
    const auto dir = scratch("track-bench");
    const Run r = run(tool() + " track --bench-objects 50 --bench-frames 60", dir);
    CHECK(r.code == 0);
    CHECK(r.out.rfind("tracking 50 objects: ", 0) == 0);
    CHECK(r.err.empty());
    const Run bad = run(tool() + " track --bench-objects -1", dir);
    CHECK(bad.code == 2);
    CHECK(bad.err.find("--bench-objects") != std::string::npos);
}

TEST_CASE("an instance image makes each object one entity carrying its id, and the file says so",
          "[cli][instances]") {
    const auto dir = scratch("instances");
    const fs::path root = fs::path(STEREOSCENE_SAMPLES_DIR) / "rendered" / "street";
    const Run r = run(
        tool() + " --kitti-root " + quote(root.string()) + " --frame 000000 --instances -o -", dir);
    REQUIRE(r.code == 0);
    const auto doc = nlohmann::json::parse(r.out);
    CHECK(doc["source"]["inputs"]["instance"].get<std::string>().find("instance/000000.png") !=
          std::string::npos);
    CHECK(doc["source"]["instances"]["encoding"] == "kitti");
    int with_id = 0;
    for (const auto& e : doc["entities"]) {
        if (e.contains("instance_id")) {
            ++with_id;
            // KITTI ids: the labelId of the entity's class in the high byte.
            CHECK(e["instance_id"].get<std::uint32_t>() >> 8 == e["class_id"].get<std::uint32_t>());
        }
    }
    CHECK(with_id >= 5);
    CHECK(doc["source"]["instances"]["entities"] == with_id);
    // batch reads the KITTI root's instance/ too.
    const fs::path out = dir / "batch";
    fs::create_directories(out);
    const Run b = run(tool() + " batch --kitti-root " + quote(root.string()) +
                          " --frames 000000 --instances -q --out-dir " + quote(out.string()),
                      dir);
    REQUIRE(b.code == 0);
    CHECK(nlohmann::json::parse(slurp(out / "000000.json"))["source"]["instances"]["entities"] ==
          with_id);
}

TEST_CASE("a bad instance image exits 1 with one line naming it and writes nothing",
          "[cli][instances]") {
    const auto dir = scratch("bad_instances");
    const fs::path root = fs::path(STEREOSCENE_SAMPLES_DIR) / "rendered" / "street";
    const fs::path json = dir / "e.json";
    const std::string inputs =
        " --kitti-root " + quote(root.string()) + " --frame 000000 -o " + quote(json.string());
    const std::string street_instance = quote((root / "instance" / "000000.png").string());
    struct Case {
        std::string flags;
        std::string says;
    };
    const std::vector<Case> cases = {
        // Another size.
        {" --instance " + quote((kSample / "semantic.png").string()), "instance image is"},
        // 8-bit colours where 16-bit ids are asked for.
        {" --instance " + quote((root / "semantic_rgb" / "000000.png").string()) +
             " --instance-encoding kitti",
         "8-bit samples where 16-bit kitti ids are expected"},
        // 16-bit ids read with the wrong encoding: their classes are not the semantic image's.
        {" --instance " + street_instance + " --instance-encoding cityscapes",
         "match the semantic image on"},
        // 16-bit ids where colours are asked for.
        {" --instance " + street_instance + " --instance-encoding colour",
         "16-bit ids where 8-bit RGB colours are expected"},
        // No semantic image to take the classes from.
        {" --instance " + street_instance + " --semantics geometry", "need the semantic image"},
        {" --instance " + quote((dir / "nope.png").string()), "nope.png"},
    };
    for (const auto& c : cases) {
        INFO(c.flags);
        const Run r = run(tool() + inputs + c.flags, dir);
        CHECK(r.code == 1);
        CHECK(count_lines(r.err) == 1);
        CHECK(r.err.find(c.says) != std::string::npos);
        CHECK_FALSE(fs::exists(json));
    }
    const Run usage = run(tool() + inputs + " --instance-encoding rgb", dir);
    CHECK(usage.code == 2);
    const Run no_root = run(tool() + sample_inputs() + " --instances -o -", dir);
    CHECK(no_root.code == 2);
    CHECK(no_root.err.find("--instances") != std::string::npos);
}

TEST_CASE(
    "batch --odometry writes each frame's pose and poses.txt, and evaluate-odometry scores it",
    "[cli][odometry]") {
    const auto dir = scratch("odometry");
    const fs::path root = fs::path(STEREOSCENE_SAMPLES_DIR) / "rendered" / "street";
    // The same stereo frame twice: the camera did not move.
    for (const char* name : {"a", "b"}) {
        fs::copy_file(root / "image_2" / "000000.png", dir / (std::string(name) + "_l.png"));
        fs::copy_file(root / "image_3" / "000000.png", dir / (std::string(name) + "_r.png"));
    }
    std::ofstream(dir / "pairs.txt") << "a_l.png a_r.png\nb_l.png b_r.png\n";
    const fs::path out = dir / "out";
    fs::create_directories(out);
    const Run b = run(tool() + " batch --pairs " + quote((dir / "pairs.txt").string()) +
                          " --calib " + quote((root / "calib" / "calib_cam_to_cam.txt").string()) +
                          " --odometry -q --out-dir " + quote(out.string()),
                      dir);
    REQUIRE(b.code == 0);
    const std::string poses = slurp(out / "poses.txt");
    CHECK(std::count(poses.begin(), poses.end(), '\n') == 2);
    const auto second = nlohmann::json::parse(slurp(out / "b_l.json"));
    REQUIRE(second["frame"].contains("pose"));
    for (int k = 0; k < 12; ++k) {
        const double identity = k % 5 == 0 ? 1.0 : 0.0;  // 0, 5, 10: the diagonal of [R | t]
        CHECK(second["frame"]["pose"][k].get<double>() == Approx(identity).margin(0.01));
    }
    const std::string poses_file = quote((out / "poses.txt").string());
    const Run same = run(tool() + " evaluate-odometry --poses " + poses_file + " --truth " +
                             poses_file + " --max-end-point-error 0 --json -",
                         dir);
    CHECK(same.code == 0);
    CHECK(nlohmann::json::parse(same.out)["end_point_m"].get<double>() == Approx(0.0));
    std::ofstream(dir / "three.txt") << poses << poses.substr(0, poses.find('\n') + 1);
    const Run other = run(tool() + " evaluate-odometry --poses " + poses_file + " --truth " +
                              quote((dir / "three.txt").string()),
                          dir);
    CHECK(other.code == 1);
    CHECK(count_lines(other.err) == 1);
    CHECK(other.err.find("differ in frames: 2 and 3") != std::string::npos);
    const Run missing =
        run(tool() + " evaluate-odometry --poses " + poses_file + " --truth nope.txt", dir);
    CHECK(missing.code == 1);
    CHECK(missing.err.find("nope.txt") != std::string::npos);
    const Run resume =
        run(tool() + " batch --pairs " + quote((dir / "pairs.txt").string()) + " --calib " +
                quote((root / "calib" / "calib_cam_to_cam.txt").string()) +
                " --odometry --resume --out-dir " + quote(out.string()),
            dir);
    CHECK(resume.code == 2);
}
