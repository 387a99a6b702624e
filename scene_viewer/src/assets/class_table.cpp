#include "scene_viewer/assets/class_table.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <stdexcept>
#include <system_error>

#include <nlohmann/json.hpp>

#include "scene_schema/entities.hpp"
#include "scene_schema/json_text.hpp"
#include "stereoscene/support/asset_dir.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"

namespace scene_viewer {
namespace {

namespace fs = std::filesystem;

class TableError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

RenderKind parse_kind(const std::string& text, const std::string& pointer) {
    if (text == "object") return RenderKind::Object;
    if (text == "ground") return RenderKind::Ground;
    if (text == "block") return RenderKind::Block;
    throw TableError(pointer + ": must be \"object\", \"ground\" or \"block\", not \"" + text +
                     "\"");
}

/// The model file named by `member` of a class row, resolved against the table's folder; empty
/// when the row has no such member.
fs::path model_path(const nlohmann::json& item, const char* member, const std::string& pointer,
                    const fs::path& folder) {
    const auto model = item.find(member);
    if (model == item.end()) return {};
    const std::string where = pointer + "/" + member;
    if (!model->is_string() || model->get<std::string>().empty()) {
        throw TableError(where + ": must be a non-empty path");
    }
    const fs::path given(model->get<std::string>());
    fs::path path = (given.is_absolute() ? given : folder / given).lexically_normal();
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) {
        throw TableError(where + ": model file not found: " + path.string());
    }
    return path;
}

RenderClass parse_class(const nlohmann::json& item, const std::string& pointer,
                        const fs::path& folder) {
    if (!item.is_object()) throw TableError(pointer + ": must be an object");
    RenderClass out;
    const auto name = item.find("name");
    if (name == item.end() || !name->is_string() || name->get<std::string>().empty()) {
        throw TableError(pointer + "/name: must be a non-empty string");
    }
    out.name = name->get<std::string>();
    const auto id = item.find("class_id");
    if (id == item.end() || !id->is_number_integer() || id->get<long long>() < 0 ||
        id->get<long long>() > 255) {
        throw TableError(pointer + "/class_id: must be an integer 0..255");
    }
    out.class_id = id->get<int>();
    const auto colour = item.find("colour");
    if (colour == item.end() || !colour->is_array() || colour->size() != 3) {
        throw TableError(pointer + "/colour: must be 3 integers 0..255");
    }
    for (std::size_t c = 0; c < 3; ++c) {
        const nlohmann::json& v = (*colour)[c];
        if (!v.is_number_integer() || v.get<long long>() < 0 || v.get<long long>() > 255) {
            throw TableError(pointer + "/colour/" + std::to_string(c) +
                             ": must be an integer 0..255");
        }
        out.colour_srgb[c] = static_cast<std::uint8_t>(v.get<int>());
    }
    const auto kind = item.find("kind");
    if (kind == item.end() || !kind->is_string()) {
        throw TableError(pointer + "/kind: must be \"object\", \"ground\" or \"block\"");
    }
    out.kind = parse_kind(kind->get<std::string>(), pointer + "/kind");
    out.model = model_path(item, "model", pointer, folder);
    out.low_model = model_path(item, "low_model", pointer, folder);
    if (!out.low_model.empty() && out.model.empty()) {
        throw TableError(pointer + "/low_model: needs a model beside it");
    }
    for (auto it = item.begin(); it != item.end(); ++it) {
        static const std::set<std::string> known = {"name", "class_id", "colour",
                                                    "kind", "model",    "low_model"};
        if (known.count(it.key()) == 0) {
            throw TableError(pointer + "/" + it.key() + ": unknown member");
        }
    }
    return out;
}

std::string read_table_text(const fs::path& path) {
    try {
        return stereoscene::support::read_text_input(path);
    } catch (const stereoscene::support::FileError& e) {
        throw TableError(e.reason());
    }
}

ClassTable parse_table(std::string_view text, const fs::path& path) {
    nlohmann::json doc;
    try {
        doc = scene_schema::parse_json(text);
    } catch (const scene_schema::SchemaError& e) {
        throw TableError((e.pointer().empty() ? "" : e.pointer() + ": ") + e.rule());
    }
    if (const auto problem =
            scene_schema::format_header_problem(doc, "stereoscene-render-classes", 1)) {
        throw TableError(*problem);
    }
    const auto classes = doc.find("classes");
    if (classes == doc.end() || !classes->is_array() || classes->empty()) {
        throw TableError("/classes: must be a non-empty array");
    }
    ClassTable table;
    table.source = path;
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    std::set<std::string> names;
    std::set<int> ids;
    for (std::size_t i = 0; i < classes->size(); ++i) {
        const std::string pointer = "/classes/" + std::to_string(i);
        RenderClass row = parse_class((*classes)[i], pointer, folder);
        if (!names.insert(row.name).second) {
            throw TableError(pointer + "/name: duplicate class name \"" + row.name + "\"");
        }
        if (!ids.insert(row.class_id).second) {
            throw TableError(pointer + "/class_id: duplicate class_id " +
                             std::to_string(row.class_id));
        }
        table.classes.push_back(std::move(row));
    }
    return table;
}

float srgb_to_linear(std::uint8_t value) {
    const float c = static_cast<float>(value) / 255.0f;
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

const RenderClass* ClassTable::find(int class_id) const {
    for (const RenderClass& c : classes) {
        if (c.class_id == class_id) return &c;
    }
    return nullptr;
}

const RenderClass* ClassTable::find(std::string_view name) const {
    for (const RenderClass& c : classes) {
        if (c.name == name) return &c;
    }
    return nullptr;
}

ClassTable load_class_table(const std::filesystem::path& path) {
    try {
        return parse_table(read_table_text(path), path);
    } catch (const std::exception& e) {
        throw std::runtime_error(path.string() + ": " + e.what());
    }
}

ClassTable parse_class_table(std::string_view text, const std::filesystem::path& path) {
    try {
        return parse_table(text, path);
    } catch (const std::exception& e) {
        throw std::runtime_error(path.string() + ": " + e.what());
    }
}

std::filesystem::path default_class_table_path() {
    return stereoscene::support::asset_dir() / "classes" / "render_classes.json";
}

const char* to_string(RenderKind kind) {
    switch (kind) {
        case RenderKind::Ground:
            return "ground";
        case RenderKind::Block:
            return "block";
        case RenderKind::Object:
            break;
    }
    return "object";
}

glm::vec4 linear_colour(const std::array<std::uint8_t, 3>& colour_srgb) {
    return {srgb_to_linear(colour_srgb[0]), srgb_to_linear(colour_srgb[1]),
            srgb_to_linear(colour_srgb[2]), 1.0f};
}

}  // namespace scene_viewer
