#include "cloud_analysis/pipeline/drive.hpp"

#include <algorithm>
#include <cstdio>
#include <set>
#include <sstream>
#include <stdexcept>

#include "stereoscene/support/file_read.hpp"

namespace cloud_analysis {
namespace {

namespace fs = std::filesystem;

/// Days from 1970-01-01 to year-month-day (proleptic Gregorian; Howard Hinnant's algorithm).
long days_from_civil(long y, unsigned m, unsigned d) {
    y -= m <= 2;
    const long era = (y >= 0 ? y : y - 399) / 400;
    const unsigned yoe = static_cast<unsigned>(y - era * 400);
    const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
    const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    return era * 146097 + static_cast<long>(doe) - 719468;
}

std::runtime_error failure(const std::string& what, const fs::path& where) {
    return std::runtime_error(what + " (" + where.string() + ")");
}

/// The calibration of a KITTI raw drive: the given file, else calib_cam_to_cam.txt beside the
/// drive's image folders or in the date folder above.
fs::path raw_calibration(const fs::path& drive, const fs::path& given) {
    if (!given.empty()) return given;
    for (const fs::path& p :
         {drive / "calib_cam_to_cam.txt",
          fs::absolute(drive).lexically_normal().parent_path() / "calib_cam_to_cam.txt"}) {
        std::error_code ec;
        if (fs::is_regular_file(p, ec)) return p;
    }
    throw failure(
        "cannot find the calibration: no calib_cam_to_cam.txt in the drive folder or "
        "its parent (give --calib)",
        drive);
}

/// image_02/timestamps.txt, one time a frame, or nothing when the file is missing.
std::vector<double> raw_timestamps(const fs::path& drive, std::size_t frames) {
    const fs::path path = drive / "image_02" / "timestamps.txt";
    std::error_code ec;
    if (!fs::exists(path, ec)) return {};
    const std::string text = stereoscene::support::read_text_input(path);
    std::vector<double> times;
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        const auto t = parse_kitti_timestamp(line);
        if (!t) {
            throw failure("cannot read timestamps: line " + std::to_string(times.size() + 1) +
                              " is not 'YYYY-MM-DD hh:mm:ss.fffffffff'",
                          path);
        }
        times.push_back(*t);
    }
    if (times.size() != frames) {
        throw failure("cannot read timestamps: " + std::to_string(times.size()) + " lines for " +
                          std::to_string(frames) + " frames",
                      path);
    }
    return times;
}

}  // namespace

std::optional<double> parse_kitti_timestamp(std::string_view text) {
    int y = 0, mo = 0, d = 0, h = 0, mi = 0, consumed = 0;
    double s = 0.0;
    const std::string line(text);
    if (std::sscanf(line.c_str(), "%4d-%2d-%2d %2d:%2d:%lf%n", &y, &mo, &d, &h, &mi, &s,
                    &consumed) != 6)
        return std::nullopt;
    if (line.find_first_not_of(" \t\r", static_cast<std::size_t>(consumed)) != std::string::npos)
        return std::nullopt;
    if (mo < 1 || mo > 12 || d < 1 || d > 31 || h > 23 || mi > 59 || !(s >= 0.0 && s < 61.0))
        return std::nullopt;
    const long days = days_from_civil(y, static_cast<unsigned>(mo), static_cast<unsigned>(d));
    return static_cast<double>(days) * 86400.0 + h * 3600.0 + mi * 60.0 + s;
}

std::vector<DriveFrame> kitti_raw_drive(const fs::path& drive, const fs::path& calibration,
                                        const fs::path& semantic_dir,
                                        const fs::path& instance_dir) {
    const fs::path left_dir = drive / "image_02" / "data";
    const fs::path right_dir = drive / "image_03" / "data";
    std::error_code ec;
    if (!fs::is_directory(left_dir, ec))
        throw failure("not a KITTI raw drive: no image_02/data folder", drive);
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(left_dir, ec)) {
        const std::string ext = entry.path().extension().string();
        if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg"))
            names.push_back(entry.path().filename().string());
    }
    if (ec) throw failure("cannot list the left images: " + ec.message(), left_dir);
    if (names.empty()) throw failure("not a KITTI raw drive: no images in image_02/data", drive);
    std::sort(names.begin(), names.end());
    const fs::path calib = raw_calibration(drive, calibration);
    const std::vector<double> times = raw_timestamps(drive, names.size());
    std::vector<DriveFrame> frames;
    for (std::size_t i = 0; i < names.size(); ++i) {
        DriveFrame f;
        f.id = fs::path(names[i]).stem().string();
        f.paths.left = left_dir / names[i];
        f.paths.right = right_dir / names[i];
        if (!fs::is_regular_file(f.paths.right, ec))
            throw failure("no right image for frame " + f.id, f.paths.right);
        if (!semantic_dir.empty()) {
            f.paths.semantic = semantic_dir / names[i];
            if (!fs::is_regular_file(f.paths.semantic, ec))
                throw failure("no semantic image for frame " + f.id, f.paths.semantic);
        }
        if (!instance_dir.empty()) {
            f.paths.instance = instance_dir / names[i];
            if (!fs::is_regular_file(f.paths.instance, ec))
                throw failure("no instance image for frame " + f.id, f.paths.instance);
        }
        f.paths.calibration = calib;
        f.paths.frame_id = f.id;
        if (!times.empty()) f.timestamp_s = times[i];
        frames.push_back(std::move(f));
    }
    return frames;
}

std::vector<DriveFrame> pair_list(std::string_view text, const fs::path& base,
                                  const fs::path& calibration, const std::string& where) {
    std::vector<DriveFrame> frames;
    std::set<std::string> ids;
    std::istringstream lines{std::string(text)};
    std::string line;
    for (int number = 1; std::getline(lines, line); ++number) {
        if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
        std::istringstream words(line);
        std::vector<std::string> paths;
        for (std::string w; words >> w;) paths.push_back(w);
        if (paths.empty()) continue;
        const std::string at = " (" + where + ", line " + std::to_string(number) + ")";
        if (paths.size() < 2 || paths.size() > 4)
            throw std::runtime_error(
                "bad frame line: expected LEFT RIGHT [SEMANTIC [INSTANCE]], got " +
                std::to_string(paths.size()) + " paths" + at);
        DriveFrame f;
        f.paths.left = base / paths[0];
        f.paths.right = base / paths[1];
        if (paths.size() >= 3) f.paths.semantic = base / paths[2];
        if (paths.size() == 4) f.paths.instance = base / paths[3];
        f.paths.calibration = calibration;
        f.id = fs::path(paths[0]).stem().string();
        if (f.id.empty() || f.id[0] == '.')
            throw std::runtime_error("bad frame line: the left image has no name" + at);
        if (!ids.insert(f.id).second)
            throw std::runtime_error("bad frame line: a second frame named '" + f.id +
                                     "' (frame ids are the left images' stems)" + at);
        f.paths.frame_id = f.id;
        frames.push_back(std::move(f));
    }
    if (frames.empty()) throw std::runtime_error("no frames (" + where + ")");
    return frames;
}

}  // namespace cloud_analysis
