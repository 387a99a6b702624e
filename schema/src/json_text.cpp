#include "scene_schema/json_text.hpp"

#include <string>
#include <vector>

#include "scene_schema/entities.hpp"

namespace scene_schema {

namespace {

using nlohmann::json;

/// Builds the document with nlohmann's own DOM builder while keeping the path to the value
/// being read, so an error can be located by a JSON pointer; refuses nesting past a depth.
class PathTrackingSax {
  public:
    PathTrackingSax(json& root, std::size_t max_depth) : dom_(root, false), max_depth_(max_depth) {}

    bool null() { return value() && dom_.null() && done(); }
    bool boolean(bool v) { return value() && dom_.boolean(v) && done(); }
    bool number_integer(json::number_integer_t v) {
        return value() && dom_.number_integer(v) && done();
    }
    bool number_unsigned(json::number_unsigned_t v) {
        return value() && dom_.number_unsigned(v) && done();
    }
    bool number_float(json::number_float_t v, const json::string_t& s) {
        return value() && dom_.number_float(v, s) && done();
    }
    bool string(json::string_t& v) { return value() && dom_.string(v) && done(); }
    bool binary(json::binary_t& v) { return value() && dom_.binary(v) && done(); }

    bool start_object(std::size_t n) { return open(false) && dom_.start_object(n); }
    bool key(json::string_t& k) {
        levels_.back().key = k;
        levels_.back().has_key = true;
        return dom_.key(k);
    }
    bool end_object() {
        levels_.pop_back();
        return dom_.end_object() && done();
    }
    bool start_array(std::size_t n) { return open(true) && dom_.start_array(n); }
    bool end_array() {
        levels_.pop_back();
        return dom_.end_array() && done();
    }

    template <class Exception>
    bool parse_error(std::size_t /*position*/, const std::string& /*last_token*/,
                     const Exception& ex) {
        std::string what = ex.what();
        // nlohmann: "[json.exception.parse_error.101] parse error at line 1, column 2: ..."
        if (auto pos = what.find("] "); pos != std::string::npos) what = what.substr(pos + 2);
        fail("not valid JSON: " + what);
        return false;
    }

    /// The first problem met, at its pointer; empty rule when the text was read.
    const std::string& pointer() const { return pointer_; }
    const std::string& rule() const { return rule_; }

  private:
    struct Level {
        bool is_array = false;
        std::size_t count = 0;  ///< elements started so far (arrays)
        std::string key;        ///< member being read (objects)
        bool has_key = false;   ///< between a member's key and the end of its value
    };

    /// A value ended: its object is between members again.
    bool done() {
        if (!levels_.empty()) levels_.back().has_key = false;
        return true;
    }

    /// Counts a value into its enclosing array.
    bool value() {
        if (!levels_.empty() && levels_.back().is_array) ++levels_.back().count;
        return true;
    }

    bool open(bool is_array) {
        if (levels_.size() >= max_depth_) {
            fail("nested deeper than " + std::to_string(max_depth_) + " levels");
            return false;
        }
        value();
        levels_.push_back({is_array, 0, {}, false});
        return true;
    }

    void fail(std::string rule) {
        if (!rule_.empty()) return;
        rule_ = std::move(rule);
        std::vector<std::string> segments;
        for (std::size_t i = 0; i < levels_.size(); ++i) {
            const Level& level = levels_[i];
            if (level.is_array) {
                // The innermost array is reading its next element; outer ones, their last.
                const bool innermost = i + 1 == levels_.size();
                segments.push_back(
                    std::to_string(innermost || level.count == 0 ? level.count : level.count - 1));
                continue;
            }
            if (!level.has_key) break;  // between members: the object itself
            std::string segment;
            for (char c : level.key.substr(0, kMaxKeyChars)) {  // RFC 6901 escaping
                if (c == '~') {
                    segment += "~0";
                } else if (c == '/') {
                    segment += "~1";
                } else {
                    segment += c;
                }
            }
            if (level.key.size() > kMaxKeyChars) segment += "...";
            segments.push_back(std::move(segment));
        }
        pointer_ = short_pointer(segments);
    }

    /// A pointer short enough for a one-line error: the first kHeadSegments segments, "...",
    /// and the last one when there are more than kHeadSegments + 1.
    static std::string short_pointer(const std::vector<std::string>& segments) {
        std::string out;
        for (std::size_t i = 0; i < segments.size(); ++i) {
            if (segments.size() > kHeadSegments + 1 && i == kHeadSegments) {
                out += "/...";
                i = segments.size() - 1;
            }
            out += '/';
            out += segments[i];
        }
        return out;
    }

    static constexpr std::size_t kMaxKeyChars = 40;  ///< of a member name in an error pointer
    static constexpr std::size_t kHeadSegments = 6;  ///< leading segments an error pointer keeps

    nlohmann::detail::json_sax_dom_parser<json> dom_;
    std::size_t max_depth_;
    std::vector<Level> levels_;
    std::string pointer_;
    std::string rule_;
};

}  // namespace

std::string json_error_text(const nlohmann::json::exception& e) {
    std::string what = e.what();
    if (what.rfind("[json.exception.", 0) == 0) {
        if (const auto pos = what.find("] "); pos != std::string::npos) what.erase(0, pos + 2);
    }
    return what;
}

std::uint64_t get_count(const nlohmann::json& value, const std::string& pointer,
                        std::uint64_t max) {
    if (!value.is_number_unsigned()) {
        throw SchemaError(pointer, "must be a non-negative integer");
    }
    const std::uint64_t v = value.get<std::uint64_t>();
    if (v > max) throw SchemaError(pointer, "must be at most " + std::to_string(max));
    return v;
}

std::optional<std::string> format_header_problem(const nlohmann::json& doc, std::string_view format,
                                                 int version) {
    if (!doc.is_object()) return "(document): must be an object";
    const auto f = doc.find("format");
    if (f == doc.end() || !f->is_string() || f->get<std::string>() != format) {
        return "/format: must be \"" + std::string(format) + "\"";
    }
    const auto v = doc.find("version");
    if (v == doc.end() || *v != version) return "/version: must be " + std::to_string(version);
    return std::nullopt;
}

json parse_json(std::string_view text, std::size_t max_depth) {
    json root;
    PathTrackingSax sax(root, max_depth);
    const bool ok = json::sax_parse(text.begin(), text.end(), &sax);
    if (!ok || !sax.rule().empty()) {
        throw SchemaError(sax.pointer(), sax.rule().empty() ? "not valid JSON" : sax.rule());
    }
    return root;
}

}  // namespace scene_schema
