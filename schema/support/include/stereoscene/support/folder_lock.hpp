#pragma once

/// One writer at a time in a folder: an advisory lock (flock(2)) on a file in it, which the
/// kernel releases when the holder exits or is killed, so a dead writer never keeps it.

#include <filesystem>
#include <string>

namespace stereoscene::support {

/// Holds `<folder>/<name>` locked for its lifetime, the file holding the holder's pid; removed
/// when released. Two processes (or two locks in one process) on the same name exclude each
/// other.
class FolderLock {
  public:
    /// Takes the lock at once or throws FileError("<folder>/<name>", "held by another writer
    /// (pid N)"); a file left by a writer that died is taken over.
    FolderLock(const std::filesystem::path& folder, const std::string& name);
    ~FolderLock();
    FolderLock(const FolderLock&) = delete;
    FolderLock& operator=(const FolderLock&) = delete;

    const std::filesystem::path& path() const { return path_; }

  private:
    std::filesystem::path path_;
    int fd_ = -1;
};

}  // namespace stereoscene::support
