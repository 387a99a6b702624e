#include "scene_schema/sequence.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "checker.hpp"
#include "scene_schema/json_text.hpp"
#include "stereoscene/support/atomic_file.hpp"

namespace scene_schema {

using detail::without;
using nlohmann::json;

namespace {

constexpr double kMaxFrameIndex = 9007199254740991.0;  // 2^53 - 1

/// The sequence index's rules over the shared checks.
class SequenceChecker : public detail::CheckerBase {
  public:
    void file(const json& value, const std::string& pointer) {
        if (!string(value, pointer)) return;
        const std::filesystem::path path(value.get<std::string>());
        bool climbs = false;
        for (const auto& part : path) climbs = climbs || part == "..";
        if (path.is_absolute() || climbs) {
            fail(pointer, "must be a relative path inside the index's folder");
        }
    }

    void frames(const json& value) {
        if (!value.is_array()) {
            fail("/frames", "must be an array");
            return;
        }
        std::optional<double> last_index;
        std::optional<double> last_time;
        for (std::size_t i = 0; i < value.size(); ++i) {
            const auto p = at("/frames", i);
            const json& f = value[i];
            if (!object(f, p)) continue;
            if (const json* v = required(f, p, "index")) {
                const auto pi = at(p, "index");
                const std::size_t before = issues.size();
                integer_in(*v, pi, 0.0, kMaxFrameIndex);
                if (issues.size() == before) {
                    const double index = v->get<double>();
                    if (last_index && index <= *last_index) {
                        fail(pi, "must be greater than the previous frame's index");
                    }
                    last_index = index;
                }
            }
            if (const json* v = required(f, p, "file")) file(*v, at(p, "file"));
            if (auto it = f.find("timestamp"); it != f.end()) {
                const auto pt = at(p, "timestamp");
                const std::size_t before = issues.size();
                bounded(*it, pt, 0.0, kMaxTimestamp_s);
                if (issues.size() == before) {
                    const double t = it->get<double>();
                    if (last_time && t < *last_time) {
                        fail(pt, "must not be earlier than the previous frame's timestamp");
                    }
                    last_time = t;
                }
            }
        }
    }

    void document(const json& value) {
        if (!object(value, "")) return;
        if (const json* v = required(value, "", "schema_version")) {
            schema_version(*v, "/schema_version");
        }
        if (const json* v = required(value, "", "id")) string(*v, "/id");
        if (auto it = value.find("fps"); it != value.end()) positive(*it, "/fps", 1e6);
        if (const json* v = required(value, "", "frames")) frames(*v);
    }
};

}  // namespace

std::vector<ValidationIssue> validate_sequence(const json& document) {
    SequenceChecker checker;
    checker.document(document);
    return std::move(checker.issues);
}

SequenceIndex sequence_from_json(const json& j) {
    auto issues = validate_sequence(j);
    if (!issues.empty()) throw SchemaError(issues.front().pointer, issues.front().rule);
    SequenceIndex index;
    index.schema_version = j.at("schema_version").get<std::string>();
    index.id = j.at("id").get<std::string>();
    if (auto it = j.find("fps"); it != j.end()) index.fps = it->get<double>();
    for (const json& f : j.at("frames")) {
        SequenceFrame frame;
        frame.index = static_cast<std::int64_t>(f.at("index").get<double>());
        frame.file = f.at("file").get<std::string>();
        if (auto it = f.find("timestamp"); it != f.end()) frame.timestamp_s = it->get<double>();
        frame.extra = without(f, {"index", "file", "timestamp"});
        index.frames.push_back(std::move(frame));
    }
    index.extra = without(j, {"schema_version", "id", "fps", "frames"});
    return index;
}

json to_json(const SequenceIndex& index) {
    json j = index.extra.is_object() ? index.extra : json::object();
    j["schema_version"] = index.schema_version;
    j["id"] = index.id;
    if (index.fps) j["fps"] = *index.fps;
    json frames = json::array();
    for (const SequenceFrame& f : index.frames) {
        json o = f.extra.is_object() ? f.extra : json::object();
        o["index"] = f.index;
        o["file"] = f.file;
        if (f.timestamp_s) o["timestamp"] = *f.timestamp_s;
        frames.push_back(std::move(o));
    }
    j["frames"] = std::move(frames);
    return j;
}

SequenceIndex read_sequence_file(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path.string() + ": cannot open: " + std::strerror(errno));
    std::ostringstream buffer;
    buffer << in.rdbuf();
    try {
        return sequence_from_json(parse_json(buffer.str()));
    } catch (const SchemaError& e) {
        const std::string where = e.pointer().empty() ? "" : e.pointer() + ": ";
        throw FileError(path.string() + ": " + where + e.rule());
    }
}

void write_sequence_file(const SequenceIndex& index, const std::filesystem::path& path,
                         stereoscene::support::FileSync sync) {
    const json j = to_json(index);
    auto issues = validate_sequence(j);
    if (!issues.empty()) throw SchemaError(issues.front().pointer, issues.front().rule);
    stereoscene::support::write_file_atomic(path, j.dump(2) + "\n", sync);
}

std::filesystem::path frame_file(const std::filesystem::path& index_path,
                                 const SequenceFrame& frame) {
    return index_path.parent_path() / frame.file;
}

bool is_sequence_index(const json& document) {
    return document.is_object() && document.contains("frames") && !document.contains("entities");
}

std::string format_kitti_poses(const std::vector<std::array<double, 12>>& poses) {
    std::string text;
    char number[32];
    for (const auto& p : poses) {
        for (std::size_t k = 0; k < 12; ++k) {
            // + 0.0: no "-0" for a zero.
            std::snprintf(number, sizeof number, "%.9e", p[k] + 0.0);
            text += number;
            text += k == 11 ? '\n' : ' ';
        }
    }
    return text;
}

}  // namespace scene_schema
