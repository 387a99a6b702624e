#include "cloud_analysis/evaluation/kitti_labels.hpp"

#include "stereoscene/support/angles.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Core>

using stereoscene::support::wrap_angle;

namespace cloud_analysis {

std::vector<KittiLabel> parse_kitti_labels(std::string_view text, const std::string& origin) {
    std::vector<KittiLabel> labels;
    std::istringstream lines{std::string(text)};
    std::string line;
    int number = 0;
    while (std::getline(lines, line)) {
        ++number;
        std::istringstream in(line);
        std::vector<std::string> cols;
        for (std::string c; in >> c;) cols.push_back(c);
        if (cols.empty()) continue;
        const auto fail = [&](const std::string& rule) {
            throw std::runtime_error("cannot read KITTI labels: line " + std::to_string(number) +
                                     ": " + rule + " (" + origin + ")");
        };
        if (cols.size() != 15 && cols.size() != 16) {
            fail("has " + std::to_string(cols.size()) + " columns, expected 15 or 16");
        }
        std::vector<double> v(cols.size(), 0.0);
        for (std::size_t i = 1; i < cols.size(); ++i) {
            try {
                std::size_t used = 0;
                v[i] = std::stod(cols[i], &used);
                if (used != cols[i].size()) throw std::invalid_argument(cols[i]);
            } catch (const std::exception&) {
                fail("column " + std::to_string(i + 1) + " is not a number: '" + cols[i] + "'");
            }
        }
        KittiLabel l;
        l.type = cols[0];
        l.truncated = v[1];
        // KITTI: 0 fully visible .. 3 unknown; -1 for DontCare. Checked before the cast, which
        // is undefined for a value outside int.
        if (!(v[2] >= -1.0 && v[2] <= 3.0)) fail("column 3 (occluded) must be -1..3");
        l.occluded = static_cast<int>(v[2]);
        l.alpha = v[3];
        for (int i = 0; i < 4; ++i) l.bbox[i] = v[4 + i];
        l.h = v[8];
        l.w = v[9];
        l.l = v[10];
        l.x = v[11];
        l.y = v[12];
        l.z = v[13];
        l.rotation_y = v[14];
        if (cols.size() == 16) l.score = v[15];
        if (l.type != "DontCare" && !(l.h > 0.0 && l.w > 0.0 && l.l > 0.0)) {
            fail("dimensions h w l must be > 0 for " + l.type);
        }
        labels.push_back(l);
    }
    return labels;
}

std::vector<KittiLabel> load_kitti_labels(const std::filesystem::path& path) {
    std::string text;
    try {
        text = stereoscene::support::read_text_input(path);
    } catch (const stereoscene::support::FileError& e) {
        throw std::runtime_error("cannot read KITTI labels: " + e.reason() + " (" + path.string() +
                                 ")");
    }
    return parse_kitti_labels(text, path.string());
}

std::optional<std::pair<std::string, int>> class_of_kitti_type(std::string_view type) {
    if (type == "Car" || type == "Van") return std::make_pair(std::string("car"), 26);
    if (type == "Truck") return std::make_pair(std::string("truck"), 27);
    if (type == "Pedestrian" || type == "Person_sitting") {
        return std::make_pair(std::string("person"), 24);
    }
    if (type == "Cyclist") return std::make_pair(std::string("rider"), 25);
    if (type == "Tram") return std::make_pair(std::string("train"), 31);
    return std::nullopt;
}

std::optional<std::string> kitti_type_of_class(std::string_view class_name) {
    if (class_name == "car") return "Car";
    if (class_name == "truck") return "Truck";
    if (class_name == "person") return "Pedestrian";
    if (class_name == "rider") return "Cyclist";
    if (class_name == "train") return "Tram";
    if (class_name == "bus" || class_name == "motorcycle" || class_name == "bicycle" ||
        class_name == "caravan" || class_name == "trailer") {
        return "Misc";
    }
    return std::nullopt;
}

LabelFrame label_frame_of(const Calibration& calibration) {
    const Eigen::Vector3d& t = calibration.reference_offset_m;
    return {t.x(), t.y(), t.z()};
}

std::optional<LabelFrame> label_frame_of(const scene_schema::EntityDocument& document) {
    if (!document.source || !document.source->is_object()) return std::nullopt;
    const auto calibration = document.source->find("calibration");
    if (calibration == document.source->end() || !calibration->is_object()) return std::nullopt;
    const auto t = calibration->find("reference_offset_m");
    if (t == calibration->end() || !t->is_array() || t->size() != 3) return std::nullopt;
    for (const auto& v : *t) {
        if (!v.is_number() || !std::isfinite(v.get<double>())) return std::nullopt;
    }
    return LabelFrame{(*t)[0].get<double>(), (*t)[1].get<double>(), (*t)[2].get<double>()};
}

std::vector<scene_schema::Entity> entities_from_kitti_labels(const std::vector<KittiLabel>& labels,
                                                             const LabelFrame& frame) {
    std::vector<scene_schema::Entity> out;
    for (std::size_t i = 0; i < labels.size(); ++i) {
        const KittiLabel& l = labels[i];
        const auto cls = class_of_kitti_type(l.type);
        if (!cls) continue;
        scene_schema::Entity e;
        e.id = cls->first + "-" + std::to_string(i + 1);
        e.class_name = cls->first;
        e.class_id = cls->second;
        if (l.type == "Car" || l.type == "Van")
            e.extra["subclass"] = l.type == "Van" ? "van" : "car";
        e.x = l.x + frame.tx_m;
        e.y = l.y - 0.5 * l.h + frame.ty_m;
        e.z = l.z + frame.tz_m;
        e.theta = l.rotation_y;
        e.W = l.w;
        e.H = l.h;
        e.L = l.l;
        e.confidence = std::clamp(l.score.value_or(1.0), 0.0, 1.0);
        e.method = "kitti_label_2";
        out.push_back(e);
    }
    return out;
}

KittiLabel kitti_label_from_entity(const scene_schema::Entity& entity,
                                   const scene_schema::CameraIntrinsics* camera,
                                   const LabelFrame& frame) {
    KittiLabel l;
    l.type = kitti_type_of_class(entity.class_name).value_or("DontCare");
    // The size family of a car (entity member `subclass`): KITTI labels vans apart.
    const auto subclass = entity.extra.find("subclass");
    if (l.type == "Car" && subclass != entity.extra.end() && *subclass == "van") l.type = "Van";
    l.h = entity.H;
    l.w = entity.W;
    l.l = entity.L;
    l.x = entity.x - frame.tx_m;
    l.y = entity.y + 0.5 * entity.H - frame.ty_m;
    l.z = entity.z - frame.tz_m;
    l.rotation_y = entity.theta;
    l.alpha = wrap_angle(entity.theta - std::atan2(l.x, l.z));
    l.score = entity.confidence;
    if (camera == nullptr || camera->fx_px <= 0.0) return l;

    const Eigen::Vector3d c(entity.x, entity.y, entity.z);
    const Eigen::Vector3d h(std::cos(entity.theta), 0.0, -std::sin(entity.theta));
    const Eigen::Vector3d a(std::sin(entity.theta), 0.0, std::cos(entity.theta));
    double u0 = std::numeric_limits<double>::max(), v0 = u0, u1 = -u0, v1 = -u0;
    for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d p = c + ((corner & 1) ? 0.5 : -0.5) * entity.L * h +
                                  ((corner & 2) ? 0.5 : -0.5) * entity.W * a +
                                  Eigen::Vector3d(0.0, ((corner & 4) ? 0.5 : -0.5) * entity.H, 0.0);
        if (p.z() < 0.1) return l;  // behind or at the camera: no 2D box
        const double u = camera->fx_px * p.x() / p.z() + camera->cx_px;
        const double v = camera->fy_px * p.y() / p.z() + camera->cy_px;
        u0 = std::min(u0, u);
        u1 = std::max(u1, u);
        v0 = std::min(v0, v);
        v1 = std::max(v1, v);
    }
    if (camera->width_px > 0 && camera->height_px > 0) {
        const double w = camera->width_px - 1.0, hgt = camera->height_px - 1.0;
        if (u1 < 0.0 || v1 < 0.0 || u0 > w || v0 > hgt) return l;
        const double area = (u1 - u0) * (v1 - v0);
        const double cu0 = std::clamp(u0, 0.0, w), cu1 = std::clamp(u1, 0.0, w);
        const double cv0 = std::clamp(v0, 0.0, hgt), cv1 = std::clamp(v1, 0.0, hgt);
        l.truncated =
            area > 0.0 ? std::clamp(1.0 - (cu1 - cu0) * (cv1 - cv0) / area, 0.0, 1.0) : 0.0;
        u0 = cu0, u1 = cu1, v0 = cv0, v1 = cv1;
    }
    l.bbox[0] = u0;
    l.bbox[1] = v0;
    l.bbox[2] = u1;
    l.bbox[3] = v1;
    return l;
}

std::string format_kitti_labels(const std::vector<KittiLabel>& labels) {
    std::string out;
    char line[512];
    for (const auto& l : labels) {
        std::snprintf(line, sizeof line,
                      "%s %.2f %d %.2f %.2f %.2f %.2f %.2f %.2f %.2f %.2f %.2f %.2f %.2f %.2f",
                      l.type.c_str(), l.truncated, l.occluded, l.alpha, l.bbox[0], l.bbox[1],
                      l.bbox[2], l.bbox[3], l.h, l.w, l.l, l.x, l.y, l.z, l.rotation_y);
        out += line;
        if (l.score) {
            std::snprintf(line, sizeof line, " %.4f", *l.score);
            out += line;
        }
        out += '\n';
    }
    return out;
}

}  // namespace cloud_analysis
