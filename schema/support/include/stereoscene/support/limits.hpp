#pragma once

/// The sizes both tools accept from outside files, checked before anything is allocated for
/// them, so a small hostile file cannot make a run take minutes or gigabytes.

#include <cstdint>
#include <new>
#include <stdexcept>
#include <string>

namespace stereoscene::support {

/// An input is larger than a limit; what() names the input, the size and the limit.
class LimitError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Upper bounds on what an input may make the tools allocate or draw. Every bound is checked
/// where the size is first known (a file's length, an image header, a glTF accessor) and a
/// larger input is refused with a one-line error that names the file and the limit.
struct Limits {
    /// Bytes of any binary input read whole: images, glTF/GLB models, clouds (1 GiB).
    std::uint64_t max_file_bytes = std::uint64_t{1} << 30;
    /// Bytes of a text input: calibrations, entity files, palettes, class tables, rigs, lists,
    /// label files (256 MiB; a 10^5-entity file is about 30 MB).
    std::uint64_t max_text_bytes = std::uint64_t{256} << 20;
    /// Pixels of one decoded image (width x height; 64 MP, 130x a KITTI frame).
    std::uint64_t max_image_pixels = std::uint64_t{64} << 20;
    /// Vertices of one glTF model, summed over every primitive that draws (4 M).
    std::uint64_t max_model_vertices = std::uint64_t{4} << 20;
    /// Entities in one entity document (10^6).
    std::uint64_t max_entities = 1'000'000;
    /// Lines of a bird's-eye ground grid, both directions together (10^4).
    std::uint64_t max_grid_lines = 10'000;
};

/// The flags that raise each limit (both tools take them, scene-render also
/// --max-model-vertices), as check_limit() hints.
inline constexpr const char* kPixelsHint = "--max-pixels raises it";
inline constexpr const char* kVerticesHint = "--max-model-vertices raises it";
inline constexpr const char* kEntitiesHint = "--max-entities raises it";

/// Runs `work`; a std::bad_alloc it throws becomes a LimitError "<what>: out of memory (...)",
/// so the one error line says what was being read or built instead of "std::bad_alloc".
template <class Work>
auto name_out_of_memory(const std::string& what, Work&& work) -> decltype(work()) {
    try {
        return work();
    } catch (const std::bad_alloc&) {
        throw LimitError(what +
                         ": out of memory (the system refused an allocation; a smaller "
                         "input or more memory is needed)");
    }
}

/// The limits in force for this process: the defaults above unless set_limits() changed them.
const Limits& limits();

/// Replaces the process's limits (a CLI does this once, from its flags, before any work).
void set_limits(const Limits& limits);

/// Throws LimitError "<what>: too large: <count> <unit> is more than the limit of <limit>;
/// <hint>" when count > limit; `hint` names the flag that raises the limit, or is empty. (Not in
/// parentheses: a trailing "(...)" is where error_line() looks for the file.)
void check_limit(const std::string& what, std::uint64_t count, std::uint64_t limit,
                 const std::string& unit, const std::string& hint = {});

}  // namespace stereoscene::support
