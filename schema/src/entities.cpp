#include "scene_schema/entities.hpp"

#include "scene_schema/json_text.hpp"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <regex>
#include <sstream>
#include <system_error>

#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/limits.hpp"

namespace scene_schema {

using nlohmann::json;

SchemaError::SchemaError(std::string pointer, std::string rule)
    : std::runtime_error(pointer + ": " + rule),
      pointer_(std::move(pointer)),
      rule_(std::move(rule)) {}

std::string ValidationIssue::message() const { return pointer + ": " + rule; }

namespace {

/// Collects issues while walking a document; `at` builds child pointers.
class Checker {
  public:
    std::vector<ValidationIssue> issues;

    void fail(const std::string& pointer, const std::string& rule) {
        issues.push_back({pointer, rule});
    }

    static std::string at(const std::string& parent, const std::string& key) {
        // RFC 6901 escaping: "~" -> "~0", "/" -> "~1".
        std::string escaped;
        for (char c : key) {
            if (c == '~') {
                escaped += "~0";
            } else if (c == '/') {
                escaped += "~1";
            } else {
                escaped += c;
            }
        }
        return parent + "/" + escaped;
    }
    static std::string at(const std::string& parent, std::size_t index) {
        return parent + "/" + std::to_string(index);
    }

    /// Returns the member when present, else records "is required" and returns nullptr.
    const json* required(const json& object, const std::string& pointer, const char* key) {
        auto it = object.find(key);
        if (it == object.end()) {
            fail(at(pointer, key), "is required");
            return nullptr;
        }
        return &*it;
    }

    bool string(const json& value, const std::string& pointer, bool non_empty = true) {
        if (!value.is_string()) {
            fail(pointer, "must be a string");
            return false;
        }
        if (non_empty && value.get_ref<const std::string&>().empty()) {
            fail(pointer, "must not be empty");
            return false;
        }
        return true;
    }

    bool number(const json& value, const std::string& pointer) {
        if (!value.is_number()) {
            fail(pointer, "must be a number");
            return false;
        }
        return true;
    }

    /// A number within [lo, hi]: the schema's "minimum"/"maximum", which also refuse the
    /// infinities a lenient JSON reader makes of 1e400.
    bool bounded(const json& value, const std::string& pointer, double lo, double hi) {
        if (!number(value, pointer)) return false;
        const double v = value.get<double>();
        if (!(v >= lo && v <= hi)) {
            fail(pointer, "must be between " + text(lo) + " and " + text(hi));
            return false;
        }
        return true;
    }

    static std::string text(double v) {
        char buffer[32];
        std::snprintf(buffer, sizeof buffer, "%.17g", v);
        return buffer;
    }

    /// JSON Schema's "integer": any number with a zero fractional part.
    bool integer(const json& value, const std::string& pointer) {
        if (value.is_number_integer()) return true;
        if (value.is_number_float()) {
            const double v = value.get<double>();
            if (std::isfinite(v) && std::floor(v) == v) return true;
        }
        fail(pointer, "must be an integer");
        return false;
    }

    bool object(const json& value, const std::string& pointer) {
        if (!value.is_object()) {
            fail(pointer, "must be an object");
            return false;
        }
        return true;
    }

    void positive(const json& value, const std::string& pointer, double hi) {
        if (!number(value, pointer)) return;
        if (!(value.get<double>() > 0.0)) {
            fail(pointer, "must be > 0");
        } else {
            bounded(value, pointer, 0.0, hi);
        }
    }

    void integer_in(const json& value, const std::string& pointer, double lo, double hi) {
        if (!integer(value, pointer)) return;
        if (lo == 0.0 && value.get<double>() < 0.0) {
            fail(pointer, "must be >= 0");
        } else if (lo == 1.0 && value.get<double>() < 1.0) {
            fail(pointer, "must be >= 1");
        } else {
            bounded(value, pointer, lo, hi);
        }
    }

    void schema_version(const json& value, const std::string& pointer) {
        if (!string(value, pointer)) return;
        static const std::regex semver(R"(^(0|[1-9][0-9]*)\.(0|[1-9][0-9]*)\.(0|[1-9][0-9]*)$)");
        std::smatch match;
        const auto& text = value.get_ref<const std::string&>();
        if (!std::regex_match(text, match, semver)) {
            fail(pointer, "must be a semantic version MAJOR.MINOR.PATCH");
            return;
        }
        if (match[1].str() != std::to_string(kSchemaMajor)) {
            fail(pointer, "unsupported major version " + match[1].str() + " (this reader reads " +
                              std::to_string(kSchemaMajor) + ".x.y)");
        }
    }

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
    }

    void entity(const json& value, const std::string& pointer) {
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
    }

    void document(const json& value) {
        if (!object(value, "")) return;
        if (const json* v = required(value, "", "schema_version")) {
            schema_version(*v, "/schema_version");
        }
        if (const json* v = required(value, "", "frame")) frame(*v, "/frame");
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
                                  " entities is more than the limit of " + std::to_string(limit));
            return;
        }
        std::map<std::string, std::size_t> first_index;
        for (std::size_t i = 0; i < entities->size(); ++i) {
            const auto p = at("/entities", i);
            const json& e = (*entities)[i];
            entity(e, p);
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

json without(const json& object, std::initializer_list<const char*> known) {
    json extra = json::object();
    for (auto it = object.begin(); it != object.end(); ++it) {
        bool is_known = false;
        for (const char* k : known) is_known = is_known || it.key() == k;
        if (!is_known) extra[it.key()] = it.value();
    }
    return extra;
}

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
    doc.frame.extra = without(f, {"id", "convention", "camera"});
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
        entity.extra = without(e, {"id", "class", "class_id", "x", "y", "z", "theta", "W", "H", "L",
                                   "point_count", "confidence", "method"});
        doc.entities.push_back(std::move(entity));
    }
    doc.extra = without(j, {"schema_version", "frame", "source", "entities"});
    return doc;
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
        for (double v : {e.x, e.y, e.z, e.theta, e.W, e.H, e.L, e.confidence}) {
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
    }
}

void write_file(const EntityDocument& document, const std::filesystem::path& path) {
    stereoscene::support::write_file_atomic(path, dump_checked(document));
}

}  // namespace scene_schema
