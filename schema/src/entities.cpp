#include "scene_schema/entities.hpp"

#include "scene_schema/json_text.hpp"

#include "checker.hpp"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <new>
#include <random>
#include <regex>
#include <sstream>
#include <system_error>

#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"

namespace scene_schema {

using detail::without;
using nlohmann::json;

SchemaError::SchemaError(std::string pointer, std::string rule)
    : std::runtime_error(pointer + ": " + rule),
      pointer_(std::move(pointer)),
      rule_(std::move(rule)) {}

std::string ValidationIssue::message() const { return pointer + ": " + rule; }

namespace {

/// The entity file's rules over the shared checks.
class Checker : public detail::CheckerBase {
  public:
    void camera(const json& value, const std::string& pointer) {
        if (!object(value, pointer)) return;
        for (const char* key : {"width", "height"}) {
            if (const json* v = required(value, pointer, key)) {
                integer_in(*v, at(pointer, key), 1.0, kMaxImageSide_px);
            }
        }
        for (const char* key : {"fx", "fy"}) {
            if (const json* v = required(value, pointer, key)) {
                positive(*v, at(pointer, key), kMaxPixelValue_px);
            }
        }
        for (const char* key : {"cx", "cy"}) {
            if (const json* v = required(value, pointer, key)) {
                bounded(*v, at(pointer, key), -kMaxPixelValue_px, kMaxPixelValue_px);
            }
        }
        if (auto it = value.find("baseline_m"); it != value.end()) {
            const auto p = at(pointer, "baseline_m");
            if (number(*it, p) && it->get<double>() < 0.0) {
                fail(p, "must be >= 0");
            } else {
                bounded(*it, p, 0.0, kMaxSize_m);
            }
        }
    }

    void frame(const json& value, const std::string& pointer) {
        if (!object(value, pointer)) return;
        if (const json* v = required(value, pointer, "id")) string(*v, at(pointer, "id"));
        if (const json* v = required(value, pointer, "convention")) {
            const auto p = at(pointer, "convention");
            if (string(*v, p) && *v != kConventionKittiCamera) {
                fail(p, std::string("must be \"") + kConventionKittiCamera + "\"");
            }
        }
        if (auto it = value.find("camera"); it != value.end()) camera(*it, at(pointer, "camera"));
        if (auto it = value.find("timestamp"); it != value.end()) {
            const auto p = at(pointer, "timestamp");
            if (number(*it, p) && it->get<double>() < 0.0) {
                fail(p, "must be >= 0");
            } else {
                bounded(*it, p, 0.0, kMaxTimestamp_s);
            }
        }
        if (auto it = value.find("pose"); it != value.end()) {
            const auto p = at(pointer, "pose");
            if (!it->is_array() || it->size() != 12) {
                fail(p, "must be an array of 12 numbers (3x4, row-major)");
            } else {
                for (std::size_t k = 0; k < 12; ++k) {
                    bounded((*it)[k], at(p, std::to_string(k)), -kMaxPoseValue, kMaxPoseValue);
                }
            }
        }
    }

    void world(const json& value, const std::string& pointer) {
        if (!object(value, pointer)) return;
        for (const char* key : {"x", "y", "z"}) {
            if (const json* v = required(value, pointer, key)) {
                bounded(*v, at(pointer, key), -kMaxWorldPosition_m, kMaxWorldPosition_m);
            }
        }
        if (const json* v = required(value, pointer, "theta")) {
            bounded(*v, at(pointer, "theta"), -kMaxTheta_rad, kMaxTheta_rad);
        }
    }

    void velocity(const json& value, const std::string& pointer) {
        if (!object(value, pointer)) return;
        for (const char* key : {"vx", "vz"}) {
            if (const json* v = required(value, pointer, key)) {
                bounded(*v, at(pointer, key), -kMaxSpeed_mps, kMaxSpeed_mps);
            }
        }
    }

    void entity(const json& value, const std::string& pointer, bool posed) {
        if (!object(value, pointer)) return;
        for (const char* key : {"id", "class"}) {
            if (const json* v = required(value, pointer, key)) string(*v, at(pointer, key));
        }
        if (const json* v = required(value, pointer, "class_id")) {
            integer_in(*v, at(pointer, "class_id"), 0.0, kMaxClassId);
        }
        for (const char* key : {"x", "y", "z"}) {
            if (const json* v = required(value, pointer, key)) {
                bounded(*v, at(pointer, key), -kMaxPosition_m, kMaxPosition_m);
            }
        }
        if (const json* v = required(value, pointer, "theta")) {
            bounded(*v, at(pointer, "theta"), -kMaxTheta_rad, kMaxTheta_rad);
        }
        for (const char* key : {"W", "H", "L"}) {
            if (const json* v = required(value, pointer, key)) {
                positive(*v, at(pointer, key), kMaxSize_m);
            }
        }
        if (const json* v = required(value, pointer, "point_count")) {
            integer_in(*v, at(pointer, "point_count"), 0.0, kMaxPointCount);
        }
        if (const json* v = required(value, pointer, "confidence")) {
            const auto p = at(pointer, "confidence");
            if (number(*v, p)) {
                const double c = v->get<double>();
                if (!(c >= 0.0 && c <= 1.0)) fail(p, "must be between 0 and 1");
            }
        }
        if (auto it = value.find("method"); it != value.end()) string(*it, at(pointer, "method"));
        if (auto it = value.find("track_id"); it != value.end()) {
            integer_in(*it, at(pointer, "track_id"), 0.0, kMaxTrackId);
        }
        if (auto it = value.find("velocity"); it != value.end()) {
            velocity(*it, at(pointer, "velocity"));
        }
        if (auto it = value.find("instance_id"); it != value.end()) {
            integer_in(*it, at(pointer, "instance_id"), 1.0, 4294967295.0);
        }
        if (auto it = value.find("world"); it != value.end()) {
            if (posed) {
                world(*it, at(pointer, "world"));
            } else {
                fail(at(pointer, "world"), "needs frame.pose (the world is the drive's)");
            }
        }
    }

    void document(const json& value) {
        if (!object(value, "")) return;
        if (const json* v = required(value, "", "schema_version")) {
            schema_version(*v, "/schema_version");
        }
        const json* f = required(value, "", "frame");
        if (f) frame(*f, "/frame");
        const bool posed = f && f->is_object() && f->contains("pose");
        if (auto it = value.find("source"); it != value.end()) object(*it, "/source");
        const json* entities = required(value, "", "entities");
        if (!entities) return;
        if (!entities->is_array()) {
            fail("/entities", "must be an array");
            return;
        }
        if (const std::uint64_t limit = stereoscene::support::limits().max_entities;
            entities->size() > limit) {
            fail("/entities", std::to_string(entities->size()) +
                                  " entities is more than the limit of " + std::to_string(limit) +
                                  "; " + stereoscene::support::kEntitiesHint);
            return;
        }
        std::map<std::string, std::size_t> first_index;
        for (std::size_t i = 0; i < entities->size(); ++i) {
            const auto p = at("/entities", i);
            const json& e = (*entities)[i];
            entity(e, p, posed);
            if (!e.is_object()) continue;
            auto id = e.find("id");
            if (id == e.end() || !id->is_string()) continue;
            auto [it, inserted] = first_index.emplace(id->get<std::string>(), i);
            if (!inserted) {
                fail(at(p, "id"), "duplicate id \"" + it->first + "\" (first at /entities/" +
                                      std::to_string(it->second) + ")");
            }
        }
    }
};

void merge_extra(json& target, const json& extra) {
    for (auto it = extra.begin(); it != extra.end(); ++it) {
        if (!target.contains(it.key())) target[it.key()] = it.value();
    }
}

}  // namespace

std::vector<ValidationIssue> validate(const json& document) {
    Checker checker;
    checker.document(document);
    return std::move(checker.issues);
}

EntityDocument from_json(const json& j) {
    auto issues = validate(j);
    if (!issues.empty()) throw SchemaError(issues.front().pointer, issues.front().rule);

    EntityDocument doc;
    doc.schema_version = j.at("schema_version").get<std::string>();
    const json& f = j.at("frame");
    doc.frame.id = f.at("id").get<std::string>();
    doc.frame.convention = f.at("convention").get<std::string>();
    if (auto it = f.find("camera"); it != f.end()) {
        CameraIntrinsics c;
        c.width_px = static_cast<int>(it->at("width").get<double>());
        c.height_px = static_cast<int>(it->at("height").get<double>());
        c.fx_px = it->at("fx").get<double>();
        c.fy_px = it->at("fy").get<double>();
        c.cx_px = it->at("cx").get<double>();
        c.cy_px = it->at("cy").get<double>();
        c.baseline_m = it->value("baseline_m", 0.0);
        doc.frame.camera = c;
    }
    if (auto it = f.find("timestamp"); it != f.end()) doc.frame.timestamp_s = it->get<double>();
    if (auto it = f.find("pose"); it != f.end()) {
        std::array<double, 12> pose{};
        for (std::size_t k = 0; k < 12; ++k) pose[k] = (*it)[k].get<double>();
        doc.frame.pose = pose;
    }
    doc.frame.extra = without(f, {"id", "convention", "camera", "timestamp", "pose"});
    if (auto it = j.find("source"); it != j.end()) doc.source = *it;
    for (const json& e : j.at("entities")) {
        Entity entity;
        entity.id = e.at("id").get<std::string>();
        entity.class_name = e.at("class").get<std::string>();
        entity.class_id = static_cast<int>(e.at("class_id").get<double>());
        entity.x = e.at("x").get<double>();
        entity.y = e.at("y").get<double>();
        entity.z = e.at("z").get<double>();
        entity.theta = e.at("theta").get<double>();
        entity.W = e.at("W").get<double>();
        entity.H = e.at("H").get<double>();
        entity.L = e.at("L").get<double>();
        entity.point_count = static_cast<std::int64_t>(e.at("point_count").get<double>());
        entity.confidence = e.at("confidence").get<double>();
        if (auto m = e.find("method"); m != e.end()) entity.method = m->get<std::string>();
        if (auto t = e.find("track_id"); t != e.end()) {
            entity.track_id = static_cast<std::int64_t>(t->get<double>());
        }
        if (auto v = e.find("velocity"); v != e.end()) {
            entity.velocity = Velocity{v->at("vx").get<double>(), v->at("vz").get<double>()};
        }
        // `world` is derived from the frame's pose: to_json writes it anew.
        entity.extra =
            without(e, {"id", "class", "class_id", "x", "y", "z", "theta", "W", "H", "L",
                        "point_count", "confidence", "method", "track_id", "velocity", "world"});
        doc.entities.push_back(std::move(entity));
    }
    doc.extra = without(j, {"schema_version", "frame", "source", "entities"});
    return doc;
}

WorldPlacement world_placement(const std::array<double, 12>& T, const Entity& e) {
    const auto turned = [&](double x, double y, double z, int row) {
        const auto r = static_cast<std::size_t>(4 * row);
        return T[r] * x + T[r + 1] * y + T[r + 2] * z;
    };
    WorldPlacement w;
    w.x = turned(e.x, e.y, e.z, 0) + T[3];
    w.y = turned(e.x, e.y, e.z, 1) + T[7];
    w.z = turned(e.x, e.y, e.z, 2) + T[11];
    const double hx = std::cos(e.theta), hz = -std::sin(e.theta);
    w.theta = std::atan2(-turned(hx, 0.0, hz, 2), turned(hx, 0.0, hz, 0));
    return w;
}

json to_json(const EntityDocument& doc) {
    json j = json::object();
    j["schema_version"] = doc.schema_version;
    json f = json::object();
    f["id"] = doc.frame.id;
    f["convention"] = doc.frame.convention;
    if (doc.frame.camera) {
        const auto& c = *doc.frame.camera;
        f["camera"] = {{"width", c.width_px},
                       {"height", c.height_px},
                       {"fx", c.fx_px},
                       {"fy", c.fy_px},
                       {"cx", c.cx_px},
                       {"cy", c.cy_px},
                       {"baseline_m", c.baseline_m}};
    }
    if (doc.frame.timestamp_s) f["timestamp"] = *doc.frame.timestamp_s;
    if (doc.frame.pose) f["pose"] = *doc.frame.pose;
    merge_extra(f, doc.frame.extra);
    j["frame"] = std::move(f);
    if (doc.source) j["source"] = *doc.source;
    json entities = json::array();
    for (const Entity& e : doc.entities) {
        json o = {{"id", e.id},
                  {"class", e.class_name},
                  {"class_id", e.class_id},
                  {"x", e.x},
                  {"y", e.y},
                  {"z", e.z},
                  {"theta", e.theta},
                  {"W", e.W},
                  {"H", e.H},
                  {"L", e.L},
                  {"point_count", e.point_count},
                  {"confidence", e.confidence}};
        if (e.method) o["method"] = *e.method;
        if (e.track_id) o["track_id"] = *e.track_id;
        if (e.velocity) o["velocity"] = {{"vx", e.velocity->vx_mps}, {"vz", e.velocity->vz_mps}};
        if (doc.frame.pose) {
            const WorldPlacement w = world_placement(*doc.frame.pose, e);
            o["world"] = {{"x", w.x}, {"y", w.y}, {"z", w.z}, {"theta", w.theta}};
        }
        merge_extra(o, e.extra);
        entities.push_back(std::move(o));
    }
    j["entities"] = std::move(entities);
    merge_extra(j, doc.extra);
    return j;
}

namespace {

/// check() on a document and its JSON form.
void check(const EntityDocument& document, const json& j) {
    for (std::size_t i = 0; i < document.entities.size(); ++i) {
        const Entity& e = document.entities[i];
        const double vx = e.velocity ? e.velocity->vx_mps : 0.0;
        const double vz = e.velocity ? e.velocity->vz_mps : 0.0;
        for (double v : {e.x, e.y, e.z, e.theta, e.W, e.H, e.L, e.confidence, vx, vz}) {
            if (!std::isfinite(v)) {
                throw SchemaError("/entities/" + std::to_string(i), "has a non-finite number");
            }
        }
    }
    auto issues = validate(j);
    if (!issues.empty()) throw SchemaError(issues.front().pointer, issues.front().rule);
}

}  // namespace

void check(const EntityDocument& document) { check(document, to_json(document)); }

std::string dump_checked(const EntityDocument& document) {
    const json j = to_json(document);
    check(document, j);
    return j.dump(2) + "\n";
}

EntityDocument parse(std::string_view text) { return from_json(parse_json(text)); }

std::string dump(const EntityDocument& document) { return to_json(document).dump(2) + "\n"; }

EntityDocument read_file(const std::filesystem::path& path) {
    const std::string text = stereoscene::support::read_text_input(path);
    try {
        return parse(text);
    } catch (const SchemaError& e) {
        const std::string where = e.pointer().empty() ? "" : e.pointer() + ": ";
        throw FileError(path.string() + ": " + where + e.rule());
    } catch (const std::bad_alloc&) {
        throw FileError(path.string() + ": out of memory reading its " +
                        std::to_string(text.size()) + " bytes of JSON");
    }
}

void write_file(const EntityDocument& document, const std::filesystem::path& path) {
    stereoscene::support::write_file_atomic(path, dump_checked(document));
}

}  // namespace scene_schema
