#include "cloud_analysis/stereo/calibration.hpp"

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "cloud_analysis/io/mat_view.hpp"
#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"
#include "stereoscene/support/atomic_file.hpp"

namespace cloud_analysis {
namespace {

using Fields = std::map<std::string, std::vector<double>>;

[[noreturn]] void fail(const std::string& origin, const std::string& field,
                       const std::string& rule) {
    throw std::runtime_error("cannot read calibration: " + field + ": " + rule + " (" + origin +
                             ")");
}

/// Bounds no real rig comes near; values past them pass the sign checks but overflow the later
/// stages (depth = fx * baseline / disparity, image sizes cast to int).
constexpr double kMaxFocalPx = 1e6;      ///< focal lengths, px
constexpr double kMaxPrincipalPx = 1e6;  ///< |cx|, |cy|, px
constexpr double kMaxBaselineM = 1e3;    ///< baseline, m
constexpr double kMaxOffsetM = 1e4;      ///< |translation| of a projection matrix, m
constexpr double kMaxImageSide = 65536;  ///< rectified width or height, px

/// Refuses a value outside [lo, hi] (NaN included) with the field's name.
void check_range(const std::string& origin, const std::string& field, double v, double lo,
                 double hi, const char* unit) {
    if (!(v >= lo && v <= hi)) {
        std::ostringstream rule;
        rule << "must be within " << lo << ".." << hi << ' ' << unit << ", is " << v;
        fail(origin, field, rule.str());
    }
}

/// An image side from the file as an int: a whole number 1..kMaxImageSide (checked before the
/// cast, which is undefined for values an int cannot hold).
int image_side(const std::string& origin, const std::string& field, double v) {
    check_range(origin, field, v, 1, kMaxImageSide, "px");
    return static_cast<int>(std::lround(v));
}

/// "key: v v v" lines (KITTI) and flat "key: v" / "key: [a, b]" YAML. Non-numeric values
/// (calib_time) are skipped.
Fields parse_lines(std::string_view text) {
    Fields fields;
    std::istringstream in{std::string(text)};
    std::string line;
    while (std::getline(in, line)) {
        if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
        const auto colon = line.find(':');
        if (colon == std::string::npos) continue;
        std::string key = line.substr(0, colon);
        key.erase(0, key.find_first_not_of(" \t"));
        key.erase(key.find_last_not_of(" \t\r") + 1);
        std::string rest = line.substr(colon + 1);
        for (char& c : rest) {
            if (c == '[' || c == ']' || c == ',') c = ' ';
        }
        std::istringstream values(rest);
        std::vector<double> numbers;
        std::string token;
        bool numeric = true;
        while (values >> token) {
            try {
                std::size_t used = 0;
                numbers.push_back(std::stod(token, &used));
                if (used != token.size()) numeric = false;
            } catch (const std::exception&) {
                numeric = false;
            }
        }
        if (numeric && !key.empty()) fields[key] = std::move(numbers);
    }
    return fields;
}

Fields parse_json(std::string_view text, const std::string& origin) {
    nlohmann::json doc;
    try {
        doc = scene_schema::parse_json(text);
    } catch (const scene_schema::SchemaError& e) {
        fail(origin, "JSON" + e.pointer(), e.rule());
    }
    if (!doc.is_object()) fail(origin, "JSON", "must be an object");
    Fields fields;
    for (const auto& [key, value] : doc.items()) {
        if (value.is_number()) {
            fields[key] = {value.get<double>()};
        } else if (value.is_array()) {
            std::vector<double> numbers;
            for (const auto& v : value) {
                if (!v.is_number()) fail(origin, key, "must hold numbers only");
                numbers.push_back(v.get<double>());
            }
            fields[key] = std::move(numbers);
        }
    }
    return fields;
}

const std::vector<double>& need(const Fields& f, const std::string& key, std::size_t count,
                                const std::string& origin) {
    const auto it = f.find(key);
    if (it == f.end()) fail(origin, key, "missing");
    if (it->second.size() != count) {
        fail(origin, key,
             "must have " + std::to_string(count) + " numbers, has " +
                 std::to_string(it->second.size()));
    }
    for (double v : it->second) {
        if (!std::isfinite(v)) fail(origin, key, "must be finite");
    }
    return it->second;
}

/// Distortion coefficients k1 k2 p1 p2 [k3]: 4 or 5 finite numbers.
std::vector<double> distortion(const Fields& f, const std::string& key, const std::string& origin) {
    const auto& d = f.at(key);
    if (d.size() != 4 && d.size() != 5) fail(origin, key, "must have 4 or 5 numbers");
    for (double v : d) {
        if (!std::isfinite(v)) fail(origin, key, "must be finite");
    }
    return d;
}

Eigen::Matrix<double, 3, 4> matrix34(const std::vector<double>& v) {
    Eigen::Matrix<double, 3, 4> m;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) m(r, c) = v[static_cast<std::size_t>(r * 4 + c)];
    return m;
}

Eigen::Matrix3d matrix33(const std::vector<double>& v) {
    Eigen::Matrix3d m;
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) m(r, c) = v[static_cast<std::size_t>(r * 3 + c)];
    return m;
}

/// Rectified rig from the two projection matrices P = K [I | t] of the left and right camera.
StereoCamera from_projections(const Eigen::Matrix<double, 3, 4>& P_left,
                              const Eigen::Matrix<double, 3, 4>& P_right, const std::string& left,
                              const std::string& right, const std::string& origin) {
    StereoCamera cam;
    cam.fx_px = P_left(0, 0);
    cam.fy_px = P_left(1, 1);
    cam.cx_px = P_left(0, 2);
    cam.cy_px = P_left(1, 2);
    cam.cx_right_px = P_right(0, 2);
    if (!(cam.fx_px > 0.0)) fail(origin, left, "fx must be > 0");
    if (!(cam.fy_px > 0.0)) fail(origin, left, "fy must be > 0");
    check_range(origin, left + " fx", cam.fx_px, 0, kMaxFocalPx, "px");
    check_range(origin, left + " fy", cam.fy_px, 0, kMaxFocalPx, "px");
    check_range(origin, left + " cx", cam.cx_px, -kMaxPrincipalPx, kMaxPrincipalPx, "px");
    check_range(origin, left + " cy", cam.cy_px, -kMaxPrincipalPx, kMaxPrincipalPx, "px");
    check_range(origin, right + " cx", cam.cx_right_px, -kMaxPrincipalPx, kMaxPrincipalPx, "px");
    if (std::abs(P_right(0, 0) - cam.fx_px) > 1e-6 * cam.fx_px) {
        fail(origin, right, "focal length differs from " + left + " (not rectified)");
    }
    cam.baseline_m = -(P_right(0, 3) - P_left(0, 3)) / cam.fx_px;
    if (!(cam.baseline_m > 0.0)) {
        fail(origin, right, "baseline must be > 0 (right camera to the right of the left one)");
    }
    check_range(origin, right + " baseline", cam.baseline_m, 0, kMaxBaselineM, "m");
    return cam;
}

/// t of P = K [I | t]: K^-1 P[:, 3].
Eigen::Vector3d projection_offset(const Eigen::Matrix<double, 3, 4>& P, const std::string& field,
                                  const std::string& origin) {
    const double tz = P(2, 3);
    const double ty = (P(1, 3) - P(1, 2) * tz) / P(1, 1);
    const double tx = (P(0, 3) - P(0, 1) * ty - P(0, 2) * tz) / P(0, 0);
    for (const double t : {tx, ty, tz}) {
        check_range(origin, field + " translation", t, -kMaxOffsetM, kMaxOffsetM, "m");
    }
    return {tx, ty, tz};
}

Calibration kitti_raw(const Fields& f, const std::string& origin, const CalibrationOptions& o) {
    const std::string l = "0" + std::to_string(o.left_camera);
    const std::string r = "0" + std::to_string(o.right_camera);
    Calibration calib;
    calib.format = "kitti_raw";
    const auto P_l = matrix34(need(f, "P_rect_" + l, 12, origin));
    Eigen::Matrix<double, 3, 4> P_r;
    if (f.count("P_rect_" + r)) {
        P_r = matrix34(need(f, "P_rect_" + r, 12, origin));
    } else {
        // Some calib_cam_to_cam.txt copies lack P_rect_03. The rig's extrinsics still give the
        // baseline: camera centre C_x = -R_0x^T T_0x in camera 0, rotated into rectified
        // camera 0 by R_rect_00; the baseline is the x offset of the two centres.
        for (const auto& key : {"R_" + l, "T_" + l, "R_" + r, "T_" + r, std::string("R_rect_00")}) {
            if (!f.count(key))
                fail(origin, "P_rect_" + r, "missing (and no " + key + " to derive it)");
        }
        const auto centre = [&](const std::string& id) -> Eigen::Vector3d {
            const Eigen::Matrix3d R = matrix33(need(f, "R_" + id, 9, origin));
            const auto& t = need(f, "T_" + id, 3, origin);
            return -R.transpose() * Eigen::Vector3d(t[0], t[1], t[2]);
        };
        const Eigen::Matrix3d R_rect0 = matrix33(need(f, "R_rect_00", 9, origin));
        const double baseline_m = (R_rect0 * (centre(r) - centre(l))).x();
        P_r = P_l;
        P_r(0, 3) = P_l(0, 3) - P_l(0, 0) * baseline_m;
        calib.note = "P_rect_" + r + " missing: baseline " + std::to_string(baseline_m) +
                     " m derived from R_" + l + "/T_" + l + "/R_" + r + "/T_" + r;
    }
    calib.camera = from_projections(P_l, P_r, "P_rect_" + l, "P_rect_" + r, origin);
    calib.reference_offset_m = projection_offset(P_l, "P_rect_" + l, origin);
    if (f.count("S_rect_" + l)) {
        const auto& s = need(f, "S_rect_" + l, 2, origin);
        calib.camera.width_px = image_side(origin, "S_rect_" + l + " width", s[0]);
        calib.camera.height_px = image_side(origin, "S_rect_" + l + " height", s[1]);
    }
    const auto raw = [&](const std::string& id,
                         const Eigen::Matrix<double, 3, 4>& P) -> std::optional<RawCamera> {
        if (!f.count("K_" + id) || !f.count("D_" + id) || !f.count("R_rect_" + id)) {
            return std::nullopt;
        }
        RawCamera cam;
        cam.K = matrix33(need(f, "K_" + id, 9, origin));
        check_range(origin, "K_" + id + " fx", cam.K(0, 0), 0, kMaxFocalPx, "px");
        check_range(origin, "K_" + id + " fy", cam.K(1, 1), 0, kMaxFocalPx, "px");
        cam.distortion = distortion(f, "D_" + id, origin);
        cam.R_rect = matrix33(need(f, "R_rect_" + id, 9, origin));
        cam.P_rect = P;
        return cam;
    };
    calib.raw_left = raw(l, P_l);
    calib.raw_right = raw(r, P_r);
    return calib;
}

Calibration kitti_object(const Fields& f, const std::string& origin, const CalibrationOptions& o) {
    const std::string l = "P" + std::to_string(o.left_camera);
    const std::string r = "P" + std::to_string(o.right_camera);
    Calibration calib;
    calib.format = "kitti_object";
    const auto P_l = matrix34(need(f, l, 12, origin));
    calib.camera = from_projections(P_l, matrix34(need(f, r, 12, origin)), l, r, origin);
    calib.reference_offset_m = projection_offset(P_l, l, origin);
    return calib;
}

Calibration simple(const Fields& f, const std::string& origin, const std::string& format) {
    Calibration calib;
    calib.format = format;
    StereoCamera& cam = calib.camera;
    cam.fx_px = need(f, "fx", 1, origin)[0];
    cam.fy_px = need(f, "fy", 1, origin)[0];
    cam.cx_px = need(f, "cx", 1, origin)[0];
    cam.cy_px = need(f, "cy", 1, origin)[0];
    cam.baseline_m = need(f, "baseline_m", 1, origin)[0];
    cam.cx_right_px = f.count("cx_right") ? need(f, "cx_right", 1, origin)[0] : cam.cx_px;
    if (f.count("width"))
        cam.width_px = image_side(origin, "width", need(f, "width", 1, origin)[0]);
    if (f.count("height"))
        cam.height_px = image_side(origin, "height", need(f, "height", 1, origin)[0]);
    if (!(cam.fx_px > 0.0)) fail(origin, "fx", "must be > 0");
    if (!(cam.fy_px > 0.0)) fail(origin, "fy", "must be > 0");
    if (!(cam.baseline_m > 0.0)) fail(origin, "baseline_m", "must be > 0");
    check_range(origin, "fx", cam.fx_px, 0, kMaxFocalPx, "px");
    check_range(origin, "fy", cam.fy_px, 0, kMaxFocalPx, "px");
    check_range(origin, "cx", cam.cx_px, -kMaxPrincipalPx, kMaxPrincipalPx, "px");
    check_range(origin, "cy", cam.cy_px, -kMaxPrincipalPx, kMaxPrincipalPx, "px");
    check_range(origin, "cx_right", cam.cx_right_px, -kMaxPrincipalPx, kMaxPrincipalPx, "px");
    check_range(origin, "baseline_m", cam.baseline_m, 0, kMaxBaselineM, "m");
    if (f.count("distortion")) {
        const std::vector<double> d = distortion(f, "distortion", origin);
        RawCamera raw;
        raw.K << cam.fx_px, 0, cam.cx_px, 0, cam.fy_px, cam.cy_px, 0, 0, 1;
        raw.distortion = d;
        raw.P_rect.leftCols<3>() = raw.K;
        calib.raw_left = raw;
        if (f.count("distortion_right")) raw.distortion = distortion(f, "distortion_right", origin);
        raw.K(0, 2) = cam.cx_right_px;
        raw.P_rect.leftCols<3>() = raw.K;
        calib.raw_right = raw;
    }
    return calib;
}

}  // namespace

void CalibrationOptions::validate() const {
    if (left_camera < 0 || left_camera > 9) {
        throw std::invalid_argument("left_camera: must be a KITTI camera index 0..9");
    }
    if (right_camera < 0 || right_camera > 9 || right_camera == left_camera) {
        throw std::invalid_argument("right_camera: must be 0..9 and differ from left_camera");
    }
    if (!(std::abs(disparity_offset_px) <= kMaxDisparityOffsetPx)) {
        throw std::invalid_argument("disparity_offset_px: must be within +-" +
                                    std::to_string(static_cast<int>(kMaxDisparityOffsetPx)) +
                                    " px");
    }
}

Calibration parse_calibration(std::string_view text, const std::string& origin,
                              const CalibrationOptions& options) {
    options.validate();
    const auto first = text.find_first_not_of(" \t\r\n");
    const bool json = first != std::string_view::npos && text[first] == '{';
    const Fields fields = json ? parse_json(text, origin) : parse_lines(text);
    Calibration calib;
    if (json) {
        calib = simple(fields, origin, "json");
    } else if (fields.count("P_rect_00") || fields.count("P_rect_02") ||
               fields.count("P_rect_0" + std::to_string(options.left_camera))) {
        calib = kitti_raw(fields, origin, options);
    } else if (fields.count("P0") || fields.count("P2")) {
        calib = kitti_object(fields, origin, options);
    } else if (fields.count("fx") || fields.count("baseline_m")) {
        calib = simple(fields, origin, "yaml");
    } else {
        fail(origin, "format",
             "not a KITTI raw (P_rect_0x), KITTI object (P2:) or fx/fy/cx/cy/baseline_m file");
    }
    calib.source = origin;
    // A disparity d reads d + offset: the depth fx B / (d - (cx - cx_right)) takes it as a right
    // principal point offset further right (the raw cameras keep the file's values).
    calib.camera.cx_right_px += options.disparity_offset_px;
    return calib;
}

Calibration load_calibration(const std::filesystem::path& path, const CalibrationOptions& options) {
    std::string text;
    try {
        text = read_text_file(path);
    } catch (const stereoscene::support::FileError& e) {
        throw std::runtime_error("cannot read calibration: " + e.reason() + " (" + path.string() +
                                 ")");
    }
    return parse_calibration(text, path.string(), options);
}

ImageU8 rectify_image(const ImageU8& raw, const RawCamera& rc, const StereoCamera& camera,
                      bool nearest) {
    const int width = camera.width_px > 0 ? camera.width_px : raw.width_px;
    const int height = camera.height_px > 0 ? camera.height_px : raw.height_px;
    cv::Mat K(3, 3, CV_64F), R(3, 3, CV_64F), P(3, 3, CV_64F);
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            K.at<double>(r, c) = rc.K(r, c);
            R.at<double>(r, c) = rc.R_rect(r, c);
            P.at<double>(r, c) = rc.P_rect(r, c);
        }
    }
    const cv::Mat D(rc.distortion, true);
    cv::Mat map_x, map_y;
    cv::initUndistortRectifyMap(K, D, R, P, cv::Size(width, height), CV_32FC1, map_x, map_y);
    const cv::Mat src = mat_view(raw);
    ImageU8 out;
    out.width_px = width;
    out.height_px = height;
    out.channels = raw.channels;
    out.data.resize(static_cast<std::size_t>(width) * height * raw.channels);
    cv::Mat dst(height, width, CV_8UC(raw.channels), out.data.data());
    cv::remap(src, dst, map_x, map_y, nearest ? cv::INTER_NEAREST : cv::INTER_LINEAR,
              cv::BORDER_CONSTANT);
    return out;
}

}  // namespace cloud_analysis
