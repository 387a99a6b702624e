#pragma once

/// Writing a run's output files as one: all of them or none, and never at the cost of a file
/// that was there before.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "stereoscene/support/atomic_file.hpp"

namespace stereoscene::support {

/// Refuses an output path before any work: an existing directory (or anything else that is not
/// a regular file or a symbolic link) at the path, or a parent that is not a directory. Throws
/// FileError "<path>: <reason>". "-" (standard output) passes.
void check_output_path(const std::filesystem::path& path);

/// The output files of one run, written together. declare() each target first, where the
/// flags are read (an existing directory or a path named twice is refused before any work);
/// stage() writes each one's bytes to a hidden temp file beside it; commit() moves them all
/// into place. If staging or committing fails, or the transaction is destroyed without a
/// commit, the temp files are removed and every target holds what it held before the run: a
/// file that existed is kept under a hidden name until the commit has finished (exchanged with
/// the new file, or hard-linked where the file system cannot exchange) and put back, never
/// removed. Not thread-safe.
class OutputTransaction {
  public:
    OutputTransaction() = default;
    OutputTransaction(const OutputTransaction&) = delete;
    OutputTransaction& operator=(const OutputTransaction&) = delete;
    ~OutputTransaction();

    /// Checks `path` with check_output_path() and that no other declared output has the same
    /// path (after resolving `.`, `..` and symbolic links of its folder); `what` names it in
    /// errors, e.g. the flag ("-o"). Throws FileError.
    void declare(const std::filesystem::path& path, const std::string& what = {});

    /// Writes `bytes` to a temp file beside `path` (declared first, or declared now).
    void stage(const std::filesystem::path& path, std::string_view bytes,
               FileSync sync = FileSync::kDurable);

    /// Renames every staged file into place, in the order staged. On failure, restores the
    /// targets already replaced and throws FileError.
    void commit();

    /// Removes the temp files and restores the targets (what the destructor does).
    void roll_back() noexcept;

  private:
    struct Output {
        std::filesystem::path path;
        std::filesystem::path key;     ///< resolved path, to find a target named twice
        std::string what;              ///< the flag or role naming it
        std::filesystem::path temp;    ///< staged bytes; empty until stage()
        std::filesystem::path backup;  ///< the earlier file while committing
        bool replaced = false;         ///< the staged file is in place
    };
    Output& find_or_declare(const std::filesystem::path& path);

    std::vector<Output> outputs_;
    bool committed_ = false;
};

}  // namespace stereoscene::support
