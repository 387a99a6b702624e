#pragma once

/// The class table: how scene-render draws each entity class (colour, kind, glTF model).
/// Format: assets/classes/render_classes.json, described in docs/models.md.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

namespace scene_viewer {

/// How an entity of a class is drawn.
enum class RenderKind {
    Object,  ///< the class's model fitted to the entity box (a box when there is no model)
    Ground,  ///< a flat patch on the box's bottom face (road, sidewalk, terrain)
    Block,   ///< the model, or a solid box when there is none (buildings, walls, fences)
};

/// One row of the class table.
struct RenderClass {
    std::string name;                           ///< class name as in entity files, e.g. "car"
    int class_id = 0;                           ///< Cityscapes labelId
    std::array<std::uint8_t, 3> colour_srgb{};  ///< palette colour, sRGB 0..255
    RenderKind kind = RenderKind::Object;
    std::filesystem::path model;  ///< glTF file (resolved against the table's folder), or empty
    /// glTF file for the class's entities whose box is lower than it is long or wide (H below
    /// max(W, L)): a hedge or a bush where `model` is a tree. Empty: `model` for every box.
    std::filesystem::path low_model;
};

/// Every class of a table file, in file order.
struct ClassTable {
    std::filesystem::path source;  ///< the file it was read from
    std::vector<RenderClass> classes;

    /// The class with this labelId, or nullptr.
    const RenderClass* find(int class_id) const;
    /// The class with this name, or nullptr.
    const RenderClass* find(std::string_view name) const;
};

/// Reads and validates a class table; model paths are resolved against the table's folder and
/// must name existing files. Throws std::runtime_error "<file>: <JSON pointer>: <reason>".
ClassTable load_class_table(const std::filesystem::path& path);

/// load_class_table() on text already in memory; `path` is the file it stands for (named in
/// errors, its folder resolves model paths). load_class_table() reads with the bounded reader
/// and calls the same parser.
ClassTable parse_class_table(std::string_view text, const std::filesystem::path& path);

/// The project's own table: classes/render_classes.json in stereoscene::support::asset_dir().
std::filesystem::path default_class_table_path();

/// "object", "ground" or "block".
const char* to_string(RenderKind kind);

/// The palette colour as a linear RGBA glTF base colour (sRGB transfer function removed).
glm::vec4 linear_colour(const std::array<std::uint8_t, 3>& colour_srgb);

}  // namespace scene_viewer
