#include "stereoscene/support/folder_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "stereoscene/support/atomic_file.hpp"

namespace stereoscene::support {
namespace {

/// The pid written in a lock file, or "" when it cannot be read.
std::string holder_of(int fd) {
    char text[32] = {};
    const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
    if (n <= 0) return {};
    std::string pid(text, static_cast<std::size_t>(n));
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    return pid;
}

}  // namespace

FolderLock::FolderLock(const std::filesystem::path& folder, const std::string& name)
    : path_(folder / name) {
    // A holder that releases removes the file: the lock taken on a file no longer at the path
    // is taken again on the new one.
    for (;;) {
        fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd_ < 0) throw FileError(path_, std::string("cannot lock: ") + std::strerror(errno));
        if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
            const int error = errno;
            const std::string pid = holder_of(fd_);
            ::close(fd_);
            fd_ = -1;
            if (error == EWOULDBLOCK) {
                throw FileError(path_, "held by another writer" +
                                           (pid.empty() ? std::string() : " (pid " + pid + ")"));
            }
            throw FileError(path_, std::string("cannot lock: ") + std::strerror(error));
        }
        struct stat held {
        }, now{};
        if (::fstat(fd_, &held) == 0 && ::stat(path_.c_str(), &now) == 0 &&
            held.st_ino == now.st_ino && held.st_dev == now.st_dev) {
            break;
        }
        ::close(fd_);
        fd_ = -1;
    }
    const std::string pid = std::to_string(::getpid()) + "\n";
    if (::ftruncate(fd_, 0) != 0 ||
        ::pwrite(fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
        // The pid is only for the message of a second writer: the lock holds without it.
    }
}

FolderLock::~FolderLock() {
    if (fd_ < 0) return;
    ::unlink(path_.c_str());
    ::close(fd_);
}

}  // namespace stereoscene::support
