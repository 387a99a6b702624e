#pragma once

/// Writing a file so that readers see the whole old file or the whole new one, never a part.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace stereoscene::support {

/// A file could not be read or written; what() starts with the file's path.
class FileError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
    /// what() is "<path>: <reason>"; path() and reason() give the two parts.
    FileError(const std::filesystem::path& path, const std::string& reason)
        : std::runtime_error(path.string() + ": " + reason), path_(path), reason_(reason) {}
    /// The file, when the error was built from its parts.
    const std::filesystem::path& path() const { return path_; }
    /// The reason without the path; what() when the error was built from one string.
    std::string reason() const { return reason_.empty() ? what() : reason_; }

  private:
    std::filesystem::path path_;
    std::string reason_;
};

/// Whether write_file_atomic waits for the disk.
enum class FileSync {
    kDurable,     ///< fsync before the rename: the file survives a power loss once written
    kAtomicOnly,  ///< no fsync: other processes, and this one after a crash, still see the
                  ///< whole old file or the whole new one; a power loss may lose it
};

/// Writes bytes to `path` atomically: a temp file in the same folder, flushed (fsync'ed when
/// `sync` is kDurable), then renamed. On failure nothing is left behind and FileError is
/// thrown.
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes,
                       FileSync sync = FileSync::kDurable);

}  // namespace stereoscene::support
