#pragma once

/// The rule checks shared by the entity file's and the sequence index's validators: each
/// records a ValidationIssue at a JSON pointer instead of throwing, so validate() reports all.

#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <regex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "scene_schema/entities.hpp"

namespace scene_schema::detail {

using nlohmann::json;

/// Collects issues while walking a document; `at` builds child pointers.
class CheckerBase {
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
};

/// The members of `object` not named in `known` (kept verbatim in a document's `extra`).
inline json without(const json& object, std::initializer_list<const char*> known) {
    json extra = json::object();
    for (auto it = object.begin(); it != object.end(); ++it) {
        bool is_known = false;
        for (const char* k : known) is_known = is_known || it.key() == k;
        if (!is_known) extra[it.key()] = it.value();
    }
    return extra;
}

}  // namespace scene_schema::detail
