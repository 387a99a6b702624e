#pragma once

/// Strict reading of JSON text exchanged between tools (RFC 8259), shared by every reader of
/// outside JSON: entity files, palettes, class tables, rigs.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
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

/// nlohmann's exception text without its "[json.exception.type_error.302] " prefix, for
/// messages that name the file themselves.
std::string json_error_text(const nlohmann::json::exception& e);

/// The non-negative integer `value` holds, or SchemaError(pointer) when it is another type, a
/// fraction, negative or above `max` (nlohmann's own get<std::size_t>() casts 1e30 or -1
/// without a check).
std::uint64_t get_count(const nlohmann::json& value, const std::string& pointer,
                        std::uint64_t max = UINT64_MAX);

/// What is wrong with the header of a tool's own JSON file (an object whose "format" member is
/// `format` and whose "version" member is `version`), as the one line a reader reports:
/// `(document): must be an object`, `/format: must be "<format>"` or `/version: must be <N>`;
/// nullopt when the header is right.
std::optional<std::string> format_header_problem(const nlohmann::json& doc, std::string_view format,
                                                 int version);

}  // namespace scene_schema
