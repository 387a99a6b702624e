#include "cloud_analysis/pipeline/resume.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string_view>

#include <scene_schema/entities.hpp>

#include "cloud_analysis/cloud/cloud_io.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"

namespace cloud_analysis {
namespace {

std::string read_all(const std::filesystem::path& path) {
    return stereoscene::support::read_file_bounded(path,
                                                   stereoscene::support::limits().max_file_bytes);
}

/// The value after `key` at the start of a header line ("POINTS 123" -> 123); throws if absent.
std::size_t header_count(const std::string& header, const std::string& key) {
    std::size_t at = 0;
    while (at < header.size()) {
        const std::size_t end = std::min(header.find('\n', at), header.size());
        const std::string_view line(header.data() + at, end - at);
        if (line.rfind(key, 0) == 0) {
            const std::string value(line.substr(key.size()));
            std::size_t used = 0;
            const unsigned long long n = std::stoull(value, &used);
            if (used != value.size()) break;
            return static_cast<std::size_t>(n);
        }
        at = end + 1;
    }
    throw std::runtime_error("header has no valid '" + key + "' line");
}

/// Header of a binary cloud: the text up to and including `terminator`.
std::string binary_header(const std::string& bytes, const std::string& terminator) {
    const std::size_t end = bytes.find(terminator);
    if (end == std::string::npos) throw std::runtime_error("no '" + terminator + "' in header");
    return bytes.substr(0, end + terminator.size());
}

std::size_t checked_binary(const std::string& bytes, const std::string& header, std::size_t points,
                           std::size_t stride) {
    if (bytes.size() != header.size() + points * stride) {
        throw std::runtime_error("size " + std::to_string(bytes.size()) + " bytes, header says " +
                                 std::to_string(points) + " points (" +
                                 std::to_string(header.size() + points * stride) + " bytes)");
    }
    return points;
}

std::size_t xyz_points(const std::string& bytes) {
    if (bytes.compare(0, kXyzHeader.size(), kXyzHeader) != 0)
        throw std::runtime_error("bad header");
    if (bytes.back() != '\n') throw std::runtime_error("last line is cut");
    const auto lines = static_cast<std::size_t>(std::count(bytes.begin(), bytes.end(), '\n'));
    return lines - 1;
}

bool png_complete(const std::string& bytes) {
    static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    static constexpr unsigned char kIend[12] = {0,   0,   0,    0,    'I',  'E',
                                                'N', 'D', 0xae, 0x42, 0x60, 0x82};
    return bytes.size() >= 20 && std::memcmp(bytes.data(), kSignature, 8) == 0 &&
           std::memcmp(bytes.data() + bytes.size() - 12, kIend, 12) == 0;
}

}  // namespace

std::vector<std::filesystem::path> frame_output_paths(const std::filesystem::path& out_dir,
                                                      const std::string& frame,
                                                      const FrameOutputs& outputs) {
    std::vector<std::filesystem::path> paths;
    if (outputs.disparity_kitti) paths.push_back(out_dir / (frame + "_disparity.png"));
    for (const auto& fmt : outputs.cloud_formats) paths.push_back(out_dir / (frame + "." + fmt));
    paths.push_back(out_dir / (frame + ".json"));
    return paths;
}

std::size_t cloud_file_points(const std::filesystem::path& path) {
    const std::string bytes = read_all(path);
    if (bytes.empty()) throw std::runtime_error("empty file");
    const std::string ext = path.extension().string();
    if (ext == ".xyz") return xyz_points(bytes);
    if (ext == ".pcd") {
        const std::string header = binary_header(bytes, "DATA binary\n");
        return checked_binary(bytes, header, header_count(header, "POINTS "), 20);
    }
    if (ext == ".ply") {
        const std::string header = binary_header(bytes, "end_header\n");
        return checked_binary(bytes, header, header_count(header, "element vertex "), 19);
    }
    throw std::runtime_error("not a cloud file extension: " + ext);
}

std::string frame_outputs_problem(const std::filesystem::path& out_dir, const std::string& frame,
                                  const FrameOutputs& outputs) {
    // The entity file is written last: without a valid one the frame is not done.
    const std::filesystem::path entities = out_dir / (frame + ".json");
    if (!std::filesystem::is_regular_file(entities)) return entities.string() + ": missing";
    try {
        const scene_schema::EntityDocument doc = scene_schema::read_file(entities);
        if (doc.frame.id != frame) {
            return entities.string() + ": names frame '" + doc.frame.id + "'";
        }
    } catch (const std::exception& e) {
        return entities.string() + ": " + e.what();
    }
    std::size_t points = 0;
    bool first = true;
    for (const auto& path : frame_output_paths(out_dir, frame, outputs)) {
        if (path == entities) continue;
        if (!std::filesystem::is_regular_file(path)) return path.string() + ": missing";
        if (path.extension() == ".png") {
            try {
                if (!png_complete(read_all(path))) return path.string() + ": not a complete PNG";
            } catch (const std::exception& e) {
                return path.string() + ": " + e.what();
            }
            continue;
        }
        try {
            const std::size_t n = cloud_file_points(path);
            if (!first && n != points) {
                return path.string() + ": " + std::to_string(n) + " points, the other clouds " +
                       std::to_string(points);
            }
            points = n;
            first = false;
        } catch (const std::exception& e) {
            return path.string() + ": " + e.what();
        }
    }
    return "";
}

std::size_t remove_stale_temporaries(const std::filesystem::path& out_dir,
                                     const std::vector<std::string>& frames,
                                     const FrameOutputs& outputs) {
    std::set<std::string> prefixes;
    for (const auto& frame : frames) {
        for (const auto& path : frame_output_paths(out_dir, frame, outputs)) {
            prefixes.insert("." + path.filename().string() + ".tmp-");
        }
    }
    std::size_t removed = 0;
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(out_dir, ec)) {
        const std::string name = entry.path().filename().string();
        if (name.size() < 2 || name[0] != '.') continue;
        const auto tmp = name.rfind(".tmp-");
        if (tmp == std::string::npos) continue;
        if (prefixes.count(name.substr(0, tmp + 5)) == 0) continue;
        std::error_code ignored;
        if (std::filesystem::remove(entry.path(), ignored)) ++removed;
    }
    return removed;
}

}  // namespace cloud_analysis
