#pragma once

/// The command-line flags that change the input limits (support::Limits), shared by both tools'
/// command lines. Header-only: only the executables, which link CLI11, include it.

#include <cstdint>
#include <optional>

#include <CLI/CLI.hpp>

#include "stereoscene/support/limits.hpp"

namespace stereoscene::support {

/// Values of the limit flags; a flag not given keeps the default of Limits.
struct LimitFlags {
    std::optional<std::uint64_t> max_pixels;          ///< Limits::max_image_pixels
    std::optional<std::uint64_t> max_model_vertices;  ///< Limits::max_model_vertices
    std::optional<std::uint64_t> max_entities;        ///< Limits::max_entities
    std::optional<std::uint64_t> max_file_mib;        ///< Limits::max_file_bytes, MiB
    std::optional<std::uint64_t> max_text_mib;        ///< Limits::max_text_bytes, MiB
};

/// Adds --max-pixels, --max-entities, --max-file-mib, --max-text-mib and, when `models`,
/// --max-model-vertices to `app` (group "Limits"); values below 1 are usage errors.
inline void add_limit_flags(CLI::App& app, LimitFlags& flags, bool models) {
    const Limits defaults;
    const auto range = CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40);
    const std::string group = "Limits (docs/reliability.md)";
    app.add_option("--max-pixels", flags.max_pixels,
                   "largest image, in pixels, read or made (default " +
                       std::to_string(defaults.max_image_pixels) + ")")
        ->check(range)
        ->group(group);
    if (models) {
        app.add_option("--max-model-vertices", flags.max_model_vertices,
                       "most vertices of one glTF model, all primitives together (default " +
                           std::to_string(defaults.max_model_vertices) + ")")
            ->check(range)
            ->group(group);
    }
    app.add_option("--max-entities", flags.max_entities,
                   "most entities in one entity file (default " +
                       std::to_string(defaults.max_entities) + ")")
        ->check(range)
        ->group(group);
    app.add_option("--max-file-mib", flags.max_file_mib,
                   "largest image, model or cloud file, MiB (default " +
                       std::to_string(defaults.max_file_bytes >> 20) + ")")
        ->check(range)
        ->group(group);
    app.add_option("--max-text-mib", flags.max_text_mib,
                   "largest calibration, entity file, table or list, MiB (default " +
                       std::to_string(defaults.max_text_bytes >> 20) + ")")
        ->check(range)
        ->group(group);
}

/// set_limits() from the flags given (the others keep their defaults); call once after the
/// command line is parsed, before any work.
inline void apply_limit_flags(const LimitFlags& flags) {
    Limits l;
    if (flags.max_pixels) l.max_image_pixels = *flags.max_pixels;
    if (flags.max_model_vertices) l.max_model_vertices = *flags.max_model_vertices;
    if (flags.max_entities) l.max_entities = *flags.max_entities;
    if (flags.max_file_mib) l.max_file_bytes = *flags.max_file_mib << 20;
    if (flags.max_text_mib) l.max_text_bytes = *flags.max_text_mib << 20;
    set_limits(l);
}

}  // namespace stereoscene::support
