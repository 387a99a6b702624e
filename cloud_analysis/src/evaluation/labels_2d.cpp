#include "cloud_analysis/evaluation/labels_2d.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <set>
#include <stdexcept>
#include <tuple>

#include <nlohmann/json.hpp>

#include "cloud_analysis/evaluation/evaluate.hpp"
#include "stereoscene/support/file_read.hpp"

namespace cloud_analysis {
namespace {

std::string lower(std::string_view text) {
    std::string out(text);
    for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

[[noreturn]] void fail(const std::string& rule, const std::string& origin) {
    throw std::runtime_error("cannot read 2D labels: " + rule + " (" + origin + ")");
}

double area(const Eigen::Vector4d& b) {
    return std::max(0.0, b[2] - b[0]) * std::max(0.0, b[3] - b[1]);
}

double intersection(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
    return area(Eigen::Vector4d(std::max(a[0], b[0]), std::max(a[1], b[1]), std::min(a[2], b[2]),
                                std::min(a[3], b[3])));
}

/// A box [u0, v0, u1, v1] of a JSON array, checked.
Eigen::Vector4d box_of(const nlohmann::json& j, const std::string& where,
                       const std::string& origin) {
    if (!j.is_array() || j.size() != 4) fail(where + ": a box is [u0, v0, u1, v1]", origin);
    Eigen::Vector4d b;
    for (int i = 0; i < 4; ++i) {
        if (!j[i].is_number()) fail(where + ": box values must be numbers", origin);
        b[i] = j[i].get<double>();
        if (!std::isfinite(b[i])) fail(where + ": box values must be finite", origin);
    }
    if (!(b[2] > b[0] && b[3] > b[1])) fail(where + ": a box needs u1 > u0 and v1 > v0", origin);
    return b;
}

Label2d object_of(const nlohmann::json& j, const std::string& where, const std::string& origin) {
    if (!j.is_object()) fail(where + ": an object is a JSON object", origin);
    Label2d l;
    if (!j.contains("type") || !j["type"].is_string()) fail(where + ": needs a \"type\"", origin);
    l.type = j["type"].get<std::string>();
    const auto category = category_of_type(l.type);
    if (!category) fail(where + ": unknown type \"" + l.type + "\"", origin);
    l.category = *category;
    if (!j.contains("box")) fail(where + ": needs a \"box\"", origin);
    l.box_px = box_of(j["box"], where, origin);
    if (j.contains("occluded")) {
        if (!j["occluded"].is_number_integer() || j["occluded"].get<int>() < 0 ||
            j["occluded"].get<int>() > 3) {
            fail(where + ": \"occluded\" is 0, 1, 2 or 3", origin);
        }
        l.occluded = j["occluded"].get<int>();
    }
    if (j.contains("truncated")) {
        if (!j["truncated"].is_number() || !(j["truncated"].get<double>() >= 0.0) ||
            j["truncated"].get<double>() > 1.0) {
            fail(where + ": \"truncated\" is a share in [0, 1]", origin);
        }
        l.truncated = j["truncated"].get<double>();
    }
    if (j.contains("track")) {
        if (!j["track"].is_string()) fail(where + ": \"track\" is a string", origin);
        l.track = j["track"].get<std::string>();
    }
    return l;
}

FrameLabels2d frame_of(const nlohmann::json& j, std::size_t index, const std::string& origin) {
    const std::string where = "frames[" + std::to_string(index) + "]";
    if (!j.is_object() || !j.contains("frame") || !j["frame"].is_string()) {
        fail(where + ": needs a \"frame\" id", origin);
    }
    FrameLabels2d f;
    f.frame = j["frame"].get<std::string>();
    if (j.contains("objects")) {
        if (!j["objects"].is_array()) fail(where + ": \"objects\" is a list", origin);
        for (std::size_t i = 0; i < j["objects"].size(); ++i) {
            f.objects.push_back(
                object_of(j["objects"][i], where + ".objects[" + std::to_string(i) + "]", origin));
        }
    }
    if (j.contains("dont_care")) {
        if (!j["dont_care"].is_array()) fail(where + ": \"dont_care\" is a list of boxes", origin);
        for (std::size_t i = 0; i < j["dont_care"].size(); ++i) {
            f.dont_care.push_back(
                box_of(j["dont_care"][i], where + ".dont_care[" + std::to_string(i) + "]", origin));
        }
    }
    return f;
}

/// The entities of a category whose projected box lies in the image.
std::vector<Scored2d> project_entities(const std::vector<scene_schema::Entity>& entities,
                                       const scene_schema::CameraIntrinsics& camera) {
    StereoCamera cam;
    cam.width_px = camera.width_px;
    cam.height_px = camera.height_px;
    cam.fx_px = camera.fx_px;
    cam.fy_px = camera.fy_px;
    cam.cx_px = cam.cx_right_px = camera.cx_px;
    cam.cy_px = camera.cy_px;
    cam.baseline_m = camera.baseline_m;

    std::vector<Scored2d> out;
    for (std::size_t i = 0; i < entities.size(); ++i) {
        const auto category = category_of_class(entities[i].class_name);
        if (!category) continue;
        const auto box = projected_box_px(entities[i], cam, cam.width_px, cam.height_px);
        if (!box) continue;
        Scored2d s;
        s.entity = i;
        s.category = *category;
        s.box_px = *box;
        s.range_m = std::hypot(entities[i].x, entities[i].z);
        out.push_back(s);
    }

    return out;
}

/// Pairs of one category that meet the rule (IoU >= min_iou; for a partly hidden label also
/// cover >= hidden_min_cover with IoU >= hidden_min_iou), taken best IoU first, one to one:
/// sets each matched entity's label and IoU; returns which labels were taken.
std::vector<bool> match_one_to_one(std::vector<Scored2d>& scored, const FrameLabels2d& labels,
                                   const Match2dOptions& options) {
    std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
    for (std::size_t e = 0; e < scored.size(); ++e) {
        const Eigen::Vector4d& eb = scored[e].box_px;
        for (std::size_t l = 0; l < labels.objects.size(); ++l) {
            const Label2d& label = labels.objects[l];
            if (label.category != scored[e].category) continue;
            const double iou = rect_iou(eb, label.box_px);
            const double cover = intersection(eb, label.box_px) / area(label.box_px);
            const bool meets = iou >= options.min_iou ||
                               (label.occluded >= 1 && cover >= options.hidden_min_cover &&
                                iou >= options.hidden_min_iou);
            if (meets) pairs.emplace_back(iou, e, l);
        }
    }
    std::sort(pairs.begin(), pairs.end(),
              [](const auto& a, const auto& b) { return std::get<0>(a) > std::get<0>(b); });
    std::vector<bool> label_taken(labels.objects.size(), false);
    for (const auto& [iou, e, l] : pairs) {
        if (scored[e].label || label_taken[l]) continue;
        scored[e].label = l;
        scored[e].iou = iou;
        label_taken[l] = true;
    }

    return label_taken;
}

}  // namespace

std::string_view category_name(Category2d category) {
    switch (category) {
        case Category2d::vehicle:
            return "vehicle";
        case Category2d::person:
            return "person";
        case Category2d::cyclist:
            return "cyclist";
    }
    return "vehicle";
}

std::optional<Category2d> category_of_type(std::string_view type) {
    const std::string t = lower(type);
    for (const char* v : {"car", "van", "truck", "bus", "tram", "train"})
        if (t == v) return Category2d::vehicle;
    for (const char* p : {"person", "pedestrian", "person_sitting"})
        if (t == p) return Category2d::person;
    for (const char* c : {"cyclist", "rider", "bicycle", "motorcycle"})
        if (t == c) return Category2d::cyclist;
    return std::nullopt;
}

std::optional<Category2d> category_of_class(std::string_view class_name) {
    for (const char* v : {"car", "truck", "bus", "train", "caravan", "trailer"})
        if (class_name == v) return Category2d::vehicle;
    if (class_name == "person") return Category2d::person;
    for (const char* c : {"rider", "bicycle", "motorcycle"})
        if (class_name == c) return Category2d::cyclist;
    return std::nullopt;
}

const FrameLabels2d* Labels2d::find(std::string_view frame) const {
    for (const auto& f : frames)
        if (f.frame == frame) return &f;
    return nullptr;
}

Labels2d parse_labels_2d(std::string_view text, const std::string& origin) {
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        fail("not JSON (syntax error at byte " + std::to_string(e.byte) + ")", origin);
    }
    if (!j.is_object() || !j.contains("frames") || !j["frames"].is_array()) {
        fail("needs a \"frames\" list", origin);
    }
    Labels2d labels;
    labels.origin = origin;
    for (const char* key : {"image_width", "image_height"}) {
        if (!j.contains(key)) continue;
        if (!j[key].is_number_integer() || j[key].get<int>() <= 0) {
            fail(std::string("\"") + key + "\" is a positive integer", origin);
        }
        (std::string(key) == "image_width" ? labels.width_px : labels.height_px) =
            j[key].get<int>();
    }
    std::set<std::string> ids;
    for (std::size_t i = 0; i < j["frames"].size(); ++i) {
        labels.frames.push_back(frame_of(j["frames"][i], i, origin));
        if (!ids.insert(labels.frames.back().frame).second) {
            fail("frame \"" + labels.frames.back().frame + "\" is labelled twice", origin);
        }
    }
    return labels;
}

FrameLabels2d labels_2d_from_kitti(const std::vector<KittiLabel>& labels, std::string frame) {
    FrameLabels2d f;
    f.frame = std::move(frame);
    for (const auto& k : labels) {
        const Eigen::Vector4d box(k.bbox[0], k.bbox[1], k.bbox[2], k.bbox[3]);
        if (!(box[2] > box[0] && box[3] > box[1])) continue;
        if (const auto category = category_of_type(k.type)) {
            Label2d l;
            l.type = k.type;
            l.category = *category;
            l.box_px = box;
            l.occluded = std::clamp(k.occluded, 0, 3);
            l.truncated = std::clamp(k.truncated, 0.0, 1.0);
            f.objects.push_back(l);
        } else if (k.type == "DontCare" || k.type == "Misc") {
            f.dont_care.push_back(box);
        }
    }
    return f;
}

Labels2d load_labels_2d(const std::filesystem::path& path) {
    if (path.extension() == ".txt") {
        Labels2d labels;
        labels.origin = path.string();
        labels.frames.push_back(
            labels_2d_from_kitti(load_kitti_labels(path), path.stem().string()));
        return labels;
    }
    std::string text;
    try {
        text = stereoscene::support::read_text_input(path);
    } catch (const stereoscene::support::FileError& e) {
        fail(e.reason(), path.string());
    }
    return parse_labels_2d(text, path.string());
}

void Match2dOptions::validate() const {
    auto share = [](double v, const char* name) {
        if (!(v > 0.0 && v <= 1.0)) {
            throw std::invalid_argument(std::string(name) + " must be in (0, 1]");
        }
    };
    share(min_iou, "min_iou");
    share(hidden_min_cover, "hidden_min_cover");
    share(hidden_min_iou, "hidden_min_iou");
    share(dont_care_cover, "dont_care_cover");
    if (!(min_height_px >= 0.0)) throw std::invalid_argument("min_height_px must be >= 0");
    if (max_occluded < 0 || max_occluded > 3) {
        throw std::invalid_argument("max_occluded must be 0..3");
    }
    if (!(max_truncated >= 0.0 && max_truncated <= 1.0)) {
        throw std::invalid_argument("max_truncated must be in [0, 1]");
    }
    if (!(max_range_m > 0.0)) throw std::invalid_argument("max_range_m must be > 0");
}

Counts2d& Counts2d::operator+=(const Counts2d& o) {
    owed += o.owed;
    found += o.found;
    counted += o.counted;
    correct += o.correct;
    ignored += o.ignored;
    return *this;
}

double Counts2d::recall() const { return owed == 0 ? 1.0 : double(found) / double(owed); }

double Counts2d::precision() const {
    return counted == 0 ? 1.0 : double(correct) / double(counted);
}

bool label_owed(const Label2d& label, const Match2dOptions& options) {
    return label.box_px[3] - label.box_px[1] >= options.min_height_px &&
           label.occluded <= options.max_occluded && label.truncated <= options.max_truncated;
}

FrameScore2d score_frame_2d(const std::vector<scene_schema::Entity>& entities,
                            const scene_schema::CameraIntrinsics& camera,
                            const FrameLabels2d& labels, const Match2dOptions& options) {
    if (!(camera.fx_px > 0.0 && camera.fy_px > 0.0) || camera.width_px <= 0 ||
        camera.height_px <= 0) {
        throw std::invalid_argument("the entities' camera has no focal length or image size");
    }
    FrameScore2d score;
    score.frame = labels.frame;
    score.entities = project_entities(entities, camera);

    const std::vector<bool> label_taken = match_one_to_one(score.entities, labels, options);
    for (auto& s : score.entities) {
        Counts2d& c = score.counts[static_cast<int>(s.category)];
        const auto in_dont_care = [&] {
            for (const auto& region : labels.dont_care) {
                if (intersection(s.box_px, region) / area(s.box_px) >= options.dont_care_cover) {
                    return true;
                }
            }
            return false;
        };
        if (s.label) {
            const bool owed = label_owed(labels.objects[*s.label], options);
            s.outcome = owed ? Scored2d::Outcome::correct : Scored2d::Outcome::ignored;
        } else if (s.range_m > options.max_range_m || in_dont_care()) {
            s.outcome = Scored2d::Outcome::ignored;
        } else {
            s.outcome = Scored2d::Outcome::false_entity;
        }
        c.ignored += s.outcome == Scored2d::Outcome::ignored;
        c.counted += s.outcome != Scored2d::Outcome::ignored;
        c.correct += s.outcome == Scored2d::Outcome::correct;
    }
    for (std::size_t l = 0; l < labels.objects.size(); ++l) {
        if (!label_owed(labels.objects[l], options)) continue;
        Counts2d& c = score.counts[static_cast<int>(labels.objects[l].category)];
        ++c.owed;
        if (label_taken[l]) {
            ++c.found;
        } else {
            score.missed.push_back(l);
        }
    }
    return score;
}

}  // namespace cloud_analysis
