#include "cloud_analysis/cloud/semantic.hpp"

#include <stdexcept>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"

#include "stereoscene/support/asset_dir.hpp"

namespace cloud_analysis {
namespace {

std::uint32_t pack(const Rgb& c) {
    return (std::uint32_t{c[0]} << 16) | (std::uint32_t{c[1]} << 8) | std::uint32_t{c[2]};
}

[[noreturn]] void fail(const std::string& origin, const std::string& pointer,
                       const std::string& rule) {
    throw std::runtime_error(origin + ": " + pointer + ": " + rule);
}

}  // namespace

Palette parse_palette(std::string_view json_text, const std::string& origin) {
    nlohmann::json doc;
    try {
        doc = scene_schema::parse_json(json_text);
    } catch (const scene_schema::SchemaError& e) {
        fail(origin, e.pointer(), "not JSON: " + e.rule());
    }
    if (!doc.is_object()) fail(origin, "", "must be an object");
    Palette palette;
    if (!doc.contains("name") || !doc["name"].is_string())
        fail(origin, "/name", "must be a string");
    palette.name = doc["name"].get<std::string>();
    if (!doc.contains("classes") || !doc["classes"].is_array() || doc["classes"].empty()) {
        fail(origin, "/classes", "must be a non-empty array");
    }
    std::unordered_map<std::uint32_t, std::size_t> seen;
    const auto& classes = doc["classes"];
    for (std::size_t i = 0; i < classes.size(); ++i) {
        const auto& c = classes[i];
        const std::string at = "/classes/" + std::to_string(i);
        if (!c.is_object()) fail(origin, at, "must be an object");
        ClassInfo info;
        if (!c.contains("name") || !c["name"].is_string() || c["name"].get<std::string>().empty()) {
            fail(origin, at + "/name", "must be a non-empty string");
        }
        info.name = c["name"].get<std::string>();
        if (!c.contains("id") || !c["id"].is_number_integer() || c["id"].get<long long>() < 0 ||
            c["id"].get<long long>() > 65535) {
            fail(origin, at + "/id", "must be an integer 0..65535");
        }
        info.id = c["id"].get<int>();
        if (c.contains("thing")) {
            if (!c["thing"].is_boolean()) fail(origin, at + "/thing", "must be true or false");
            info.thing = c["thing"].get<bool>();
        }
        if (!c.contains("colour") || !c["colour"].is_array() || c["colour"].size() != 3) {
            fail(origin, at + "/colour", "must be [r, g, b]");
        }
        for (int k = 0; k < 3; ++k) {
            const auto& v = c["colour"][static_cast<std::size_t>(k)];
            if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > 255) {
                fail(origin, at + "/colour/" + std::to_string(k), "must be an integer 0..255");
            }
            info.colour[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(v.get<int>());
        }
        const auto [it, fresh] = seen.emplace(pack(info.colour), i);
        if (!fresh) {
            fail(origin, at + "/colour", "same colour as /classes/" + std::to_string(it->second));
        }
        palette.classes.push_back(std::move(info));
    }
    if (palette.classes.size() >= kVoidClass) fail(origin, "/classes", "too many classes");
    return palette;
}

std::filesystem::path bundled_palette_dir() {
    return stereoscene::support::asset_dir() / "palettes";
}

Palette load_palette(const std::string& name_or_path) {
    std::filesystem::path path(name_or_path);
    if (!path.has_extension() && !path.has_parent_path()) {
        path = bundled_palette_dir() / (name_or_path + ".json");
    }
    return parse_palette(read_text_file(path), path.string());
}

std::uint16_t find_colour(const Palette& palette, const Rgb& colour) {
    for (std::size_t i = 0; i < palette.classes.size(); ++i) {
        if (palette.classes[i].colour == colour) return static_cast<std::uint16_t>(i);
    }
    return kVoidClass;
}

std::uint16_t find_class(const Palette& palette, std::string_view name) {
    for (std::size_t i = 0; i < palette.classes.size(); ++i) {
        if (palette.classes[i].name == name) return static_cast<std::uint16_t>(i);
    }
    return kVoidClass;
}

ClassImage classify_pixels(const ImageU8& semantic_rgb, const Palette& palette) {
    if (semantic_rgb.channels != 3) {
        throw std::invalid_argument("semantic image must have 3 colour channels, has " +
                                    std::to_string(semantic_rgb.channels));
    }
    std::unordered_map<std::uint32_t, std::uint16_t> lookup;
    for (std::size_t i = 0; i < palette.classes.size(); ++i) {
        lookup.emplace(pack(palette.classes[i].colour), static_cast<std::uint16_t>(i));
    }
    ClassImage out;
    out.width_px = semantic_rgb.width_px;
    out.height_px = semantic_rgb.height_px;
    const std::size_t n = static_cast<std::size_t>(out.width_px) * out.height_px;
    out.class_index.resize(n);
    // Semantic images are made of long runs of one colour: cache the previous lookup.
    std::uint32_t last_key = 0xFFFFFFFFu;
    std::uint16_t last_index = kVoidClass;
    const std::uint8_t* p = semantic_rgb.data.data();
    for (std::size_t i = 0; i < n; ++i, p += 3) {
        const std::uint32_t key = (std::uint32_t{p[0]} << 16) | (std::uint32_t{p[1]} << 8) | p[2];
        if (key != last_key) {
            const auto it = lookup.find(key);
            last_index = it == lookup.end() ? kVoidClass : it->second;
            last_key = key;
        }
        out.class_index[i] = last_index;
        if (last_index == kVoidClass) ++out.void_pixels;
    }
    return out;
}

}  // namespace cloud_analysis
