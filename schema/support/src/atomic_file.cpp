#include "stereoscene/support/atomic_file.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include <fcntl.h>  // AT_FDCWD
#include <stdio.h>  // renameat2, RENAME_EXCHANGE (glibc >= 2.28)
#include <sys/stat.h>
#include <unistd.h>

namespace stereoscene::support {

void write_file_atomic(const std::filesystem::path& path, std::string_view bytes, FileSync sync) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
        // renameat2's exchange below would swap the directory aside.
        throw FileError(path.string() + ": is a directory, refused as an output");
    }
    const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
    std::string temp = (dir / ("." + path.filename().string() + ".tmp-XXXXXX")).string();
    const int fd = ::mkstemp(temp.data());
    if (fd < 0) {
        throw FileError(path.string() +
                        ": cannot create a temporary file: " + std::strerror(errno));
    }
    auto fail = [&](const char* what) {
        const int err = errno;
        ::close(fd);
        ::unlink(temp.c_str());
        throw FileError(path.string() + ": " + what + ": " + std::strerror(err));
    };
    const char* data = bytes.data();
    std::size_t left = bytes.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, data, left);
        if (n < 0) {
            if (errno == EINTR) continue;
            fail("write failed");
        }
        data += n;
        left -= static_cast<std::size_t>(n);
    }
    if (::fchmod(fd, 0644) != 0) fail("chmod failed");
    if (sync == FileSync::kDurable && ::fsync(fd) != 0) fail("fsync failed");
    if (::close(fd) != 0) {
        const int err = errno;
        ::unlink(temp.c_str());
        throw FileError(path.string() + ": close failed: " + std::strerror(err));
    }
    if (sync == FileSync::kAtomicOnly) {
        // Exchange the new file with the old one, then unlink the old: ext4 writes a file
        // renamed over another out to disk at once (its replace-by-rename heuristic, about 1 ms
        // per MB here), which an exchange, just as atomic for readers, does not do. No old file
        // (ENOENT) or a file system without exchanges: a plain rename below.
        if (::renameat2(AT_FDCWD, temp.c_str(), AT_FDCWD, path.c_str(), RENAME_EXCHANGE) == 0) {
            ::unlink(temp.c_str());  // the old file now; the new one is in place either way
            return;
        }
    }
    if (std::rename(temp.c_str(), path.c_str()) != 0) {
        const int err = errno;
        ::unlink(temp.c_str());
        throw FileError(path.string() + ": rename failed: " + std::strerror(err));
    }
}

}  // namespace stereoscene::support
