#pragma once

/// Strict reading of JSON text exchanged between tools (RFC 8259), shared by every reader of
/// outside JSON: entity files, palettes, class tables, rigs.

#include <cstddef>
#include <string_view>

#include <nlohmann/json.hpp>

namespace scene_schema {

/// Deepest nesting of arrays and objects a reader accepts. The entity format itself nests four
/// levels; the limit leaves room for free-form members while keeping every later walk of the
/// document (validation, copies, dumps) far from the stack's end.
inline constexpr std::size_t kMaxJsonDepth = 256;

/// Parses JSON text strictly: no NaN or Infinity literals, no number that
/// overflows a double, at most `max_depth` levels of nesting. Throws SchemaError at the JSON
/// pointer where the text breaks (the enclosing member or element), with a one-line rule that
/// names the line and column of syntax errors. A leading UTF-8 byte order mark is skipped, as
/// RFC 8259 section 8.1 allows.
nlohmann::json parse_json(std::string_view text, std::size_t max_depth = kMaxJsonDepth);

}  // namespace scene_schema
