#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene_viewer/assets/image_io.hpp"
#include "scene_viewer/sensors/stereo_sensors.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/output_transaction.hpp"

namespace scene_viewer {

namespace {

std::string numbers(const std::vector<double>& values) {
    std::string out;
    char buffer[32];
    for (double v : values) {
        std::snprintf(buffer, sizeof buffer, "%.12e", v);
        if (!out.empty()) out += ' ';
        out += buffer;
    }
    return out;
}

std::string as_text(const std::vector<unsigned char>& bytes) {
    return std::string(bytes.begin(), bytes.end());
}

}  // namespace

std::vector<unsigned char> encode_png_rgb8(const ImageRgb8& image) {
    if (image.width <= 0 || image.height <= 0 ||
        image.pixels.size() != static_cast<std::size_t>(image.width) * image.height * 3)
        throw std::invalid_argument("PNG: RGB image size does not match its pixel data");
    return encode_png_samples(image.pixels.data(), image.width, image.height, 8, 2, 3, 6);
}

std::vector<unsigned char> encode_png_u16(const ImageU16& image) {
    if (image.width <= 0 || image.height <= 0 ||
        image.values.size() != static_cast<std::size_t>(image.width) * image.height)
        throw std::invalid_argument("PNG: 16-bit image size does not match its values");
    std::vector<unsigned char> raw;
    raw.reserve(image.values.size() * 2);
    for (std::uint16_t v : image.values) {
        raw.push_back(static_cast<unsigned char>(v >> 8));
        raw.push_back(static_cast<unsigned char>(v & 0xff));
    }
    return encode_png_samples(raw.data(), image.width, image.height, 16, 0, 2, 6);
}

std::string format_kitti_calib(const StereoRig& rig) {
    rig.validate();
    const double fx = rig.fx_px, fy = rig.fy_px, cx = rig.cx_px, cy = rig.cy_px;
    const std::vector<double> size = {static_cast<double>(rig.width_px),
                                      static_cast<double>(rig.height_px)};
    const std::vector<double> identity = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    std::string out = "calib_time: synthetic (scene-render sensors)\n";
    out += "S_rect_02: " + numbers(size) + "\n";
    out += "R_rect_02: " + numbers(identity) + "\n";
    out += "P_rect_02: " + numbers({fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0}) + "\n";
    out += "S_rect_03: " + numbers(size) + "\n";
    out += "R_rect_03: " + numbers(identity) + "\n";
    out +=
        "P_rect_03: " + numbers({fx, 0, cx, -fx * rig.baseline_m, 0, fy, cy, 0, 0, 0, 1, 0}) + "\n";
    return out;
}

StereoRig parse_kitti_calib(const std::string& text) {
    std::map<std::string, std::vector<double>> fields;
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
        const auto colon = line.find(':');
        if (colon == std::string::npos) continue;
        std::istringstream values(line.substr(colon + 1));
        std::vector<double> v;
        double d = 0.0;
        while (values >> d) v.push_back(d);
        fields[line.substr(0, colon)] = v;
    }
    auto need = [&](const std::string& key, std::size_t count) -> const std::vector<double>& {
        auto it = fields.find(key);
        if (it == fields.end()) throw std::invalid_argument(key + ": missing");
        if (it->second.size() != count)
            throw std::invalid_argument(key + ": expected " + std::to_string(count) + " numbers");
        return it->second;
    };
    const auto& p2 = need("P_rect_02", 12);
    const auto& p3 = need("P_rect_03", 12);
    const auto& s = need("S_rect_02", 2);
    StereoRig rig;
    rig.width_px = static_cast<int>(std::lround(s[0]));
    rig.height_px = static_cast<int>(std::lround(s[1]));
    rig.fx_px = p2[0];
    rig.cx_px = p2[2];
    rig.fy_px = p2[5];
    rig.cy_px = p2[6];
    if (!(rig.fx_px > 0.0)) throw std::invalid_argument("P_rect_02: fx must be > 0");
    rig.baseline_m = (p2[3] - p3[3]) / rig.fx_px;
    rig.validate();
    return rig;
}

void check_frame_name(const std::string& frame_name) {
    if (frame_name.empty() || frame_name.find_first_of("/\\") != std::string::npos ||
        frame_name == "." || frame_name == "..")
        throw std::invalid_argument("frame name '" + frame_name + "' must be a plain file stem");
}

std::string format_visibility_json(const StereoFrame& frame) {
    nlohmann::ordered_json entities = nlohmann::ordered_json::array();
    for (const auto& v : frame.visibility) {
        entities.push_back(
            {{"id", v.id},
             {"class", v.class_name},
             {"class_id", v.class_id},
             {"instance", v.instance},
             {"visible_px", v.visible_px},
             {"unoccluded_px", v.unoccluded_px},
             {"in_view_fraction", std::round(v.in_view_fraction * 10000.0) / 10000.0},
             {"visible_fraction", std::round(v.visible_fraction() * 10000.0) / 10000.0}});
    }
    nlohmann::ordered_json out = {{"width_px", frame.rig.width_px},
                                  {"height_px", frame.rig.height_px},
                                  {"entities", entities}};
    return out.dump(2) + "\n";
}

std::vector<std::string> kitti_layout_names(const std::string& frame_name) {
    check_frame_name(frame_name);
    const std::string png = frame_name + ".png";
    return {"calib/calib_cam_to_cam.txt",
            "depth/" + png,
            "disp_occ_0/" + png,
            "image_2/" + png,
            "image_3/" + png,
            "instance/" + png,
            "semantic_rgb/" + png,
            "visibility/" + frame_name + ".json"};
}

bool files_complete(const std::filesystem::path& root, const std::vector<std::string>& relative) {
    namespace fs = std::filesystem;
    bool complete = true;
    for (const auto& name : relative) {
        const fs::path path = root / name;
        std::error_code ec;
        const std::string hidden = "." + path.filename().string() + ".";
        for (const auto& entry : fs::directory_iterator(path.parent_path(), ec)) {
            const std::string file = entry.path().filename().string();
            if (file.rfind(hidden + "tmp-", 0) == 0 || file.rfind(hidden + "old-", 0) == 0) {
                std::error_code ignored;
                fs::remove(entry.path(), ignored);
            }
        }
        if (!fs::is_regular_file(path, ec)) complete = false;
    }
    return complete;
}

std::map<std::string, std::string> kitti_layout_files(const StereoFrame& frame,
                                                      const std::string& frame_name) {
    check_frame_name(frame_name);
    const std::string png = frame_name + ".png";
    return {{"image_2/" + png, as_text(encode_png_rgb8(frame.left))},
            {"image_3/" + png, as_text(encode_png_rgb8(frame.right))},
            {"semantic_rgb/" + png, as_text(encode_png_rgb8(frame.semantic))},
            {"instance/" + png, as_text(encode_png_u16(frame.instance))},
            {"disp_occ_0/" + png, as_text(encode_png_u16(frame.disparity))},
            {"depth/" + png, as_text(encode_png_u16(frame.depth_mm))},
            {"visibility/" + frame_name + ".json", format_visibility_json(frame)},
            {"calib/calib_cam_to_cam.txt", format_kitti_calib(frame.rig)}};
}

void write_files(const std::filesystem::path& root,
                 const std::map<std::string, std::string>& files) {
    namespace fs = std::filesystem;
    std::vector<fs::path> created;  // folders this call made, outermost first
    auto remove_created = [&] {
        std::error_code ignored;
        for (auto it = created.rbegin(); it != created.rend(); ++it) fs::remove(*it, ignored);
    };
    try {
        stereoscene::support::OutputTransaction outputs;
        for (const auto& [relative, bytes] : files) {
            const fs::path rel(relative);
            const fs::path normal = rel.lexically_normal();
            if (rel.is_absolute() || normal.empty() || *normal.begin() == "..") {
                throw stereoscene::support::FileError(root / rel, "leaves the output folder");
            }
            const fs::path path = root / rel;
            std::vector<fs::path> missing;
            for (fs::path p = path.parent_path(); !p.empty() && !fs::exists(p);
                 p = p.parent_path()) {
                missing.push_back(p);
            }
            for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
                std::error_code ec;
                if (!fs::create_directory(*it, ec) && ec) {
                    throw stereoscene::support::FileError(*it, ec.message());
                }
                created.push_back(*it);
            }
            outputs.stage(path, bytes);
        }
        outputs.commit();
    } catch (...) {
        remove_created();
        throw;
    }
}

}  // namespace scene_viewer
