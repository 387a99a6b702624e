#include "stereoscene/support/output_transaction.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <system_error>

#include <fcntl.h>
#include <stdio.h>  // renameat2, RENAME_EXCHANGE (glibc >= 2.28)
#include <sys/stat.h>
#include <unistd.h>

namespace stereoscene::support {
namespace {

namespace fs = std::filesystem;

fs::path folder_of(const fs::path& path) {
    return path.has_parent_path() ? path.parent_path() : fs::path(".");
}

/// A fresh hidden name beside `path`: `.NAME.<tag>-XXXXXX`, created empty by mkstemp.
fs::path unique_beside(const fs::path& path, const char* tag) {
    std::string name =
        (folder_of(path) / ("." + path.filename().string() + "." + tag + "-XXXXXX")).string();
    const int fd = ::mkstemp(name.data());
    if (fd < 0) {
        throw FileError(path,
                        std::string("cannot create a temporary file: ") + std::strerror(errno));
    }
    ::close(fd);
    return name;
}

/// The path with its folder resolved, so "a/../out.png" and "out.png" are one target.
fs::path resolved(const fs::path& path) {
    std::error_code ec;
    const fs::path folder = fs::weakly_canonical(fs::absolute(folder_of(path)), ec);
    return (ec ? fs::absolute(folder_of(path)) : folder) / path.filename();
}

}  // namespace

void check_output_path(const fs::path& path) {
    if (path == "-") return;
    if (path.empty() || path.filename().empty() || path.filename() == "." ||
        path.filename() == "..") {
        throw FileError(path, "not a file name");
    }
    struct stat st {};
    if (::lstat(path.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) throw FileError(path, "is a directory, refused as an output");
        if (!S_ISREG(st.st_mode) && !S_ISLNK(st.st_mode)) {
            throw FileError(path, "exists and is not a regular file, refused as an output");
        }
    }
    const fs::path folder = folder_of(path);
    std::error_code ec;
    if (!fs::is_directory(folder, ec)) {
        throw FileError(path, "no such folder " + folder.string());
    }
}

OutputTransaction::~OutputTransaction() {
    if (!committed_) roll_back();
}

OutputTransaction::Output& OutputTransaction::find_or_declare(const fs::path& path) {
    for (Output& o : outputs_) {
        if (o.path == path) return o;
    }
    declare(path);
    return outputs_.back();
}

void OutputTransaction::declare(const fs::path& path, const std::string& what) {
    check_output_path(path);
    const fs::path key = resolved(path);
    for (const Output& o : outputs_) {
        if (o.key == key) {
            const std::string first = o.what.empty() ? o.path.string() : o.what;
            throw FileError(path, (what.empty() ? std::string("output") : what) +
                                      " is the same file as " + first + ", refused");
        }
    }
    outputs_.push_back(Output{path, key, what, {}, {}, false});
}

void OutputTransaction::stage(const fs::path& path, std::string_view bytes, FileSync sync) {
    Output& out = find_or_declare(path);
    if (!out.temp.empty()) throw FileError(path, "staged twice");
    out.temp = unique_beside(path, "tmp");
    const int fd = ::open(out.temp.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
    const char* failed = fd < 0 ? "cannot open a temporary file" : nullptr;
    for (std::size_t done = 0; failed == nullptr && done < bytes.size();) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) failed = "write failed";
        done += n > 0 ? static_cast<std::size_t>(n) : 0;
    }
    if (failed == nullptr && ::fchmod(fd, 0644) != 0) failed = "chmod failed";
    if (failed == nullptr && sync == FileSync::kDurable && ::fsync(fd) != 0) {
        failed = "fsync failed";
    }
    const int err = errno;
    if (fd >= 0 && ::close(fd) != 0 && failed == nullptr) failed = "close failed";
    if (failed != nullptr) {
        ::unlink(out.temp.c_str());
        out.temp.clear();
        throw FileError(path, std::string(failed) + ": " + std::strerror(err));
    }
}

void OutputTransaction::commit() {
    try {
        for (Output& o : outputs_) {
            if (o.temp.empty()) continue;
            struct stat st {};
            if (::lstat(o.path.c_str(), &st) == 0) {
                if (S_ISDIR(st.st_mode)) throw FileError(o.path, "is a directory, refused");
                // Exchange: the new file takes the target's name and the earlier file takes
                // the temp name, which keeps it until the commit has finished. Unlike a rename
                // over a file, an exchange does not make ext4 write the file out at once
                // (its replace-by-rename heuristic, about 1 ms per MB).
                if (::renameat2(AT_FDCWD, o.temp.c_str(), AT_FDCWD, o.path.c_str(),
                                RENAME_EXCHANGE) == 0) {
                    o.backup = o.temp;
                    o.temp.clear();
                    o.replaced = true;
                    continue;
                }
                // A file system without exchanges: keep the earlier file by a hard link.
                o.backup = unique_beside(o.path, "old");
                ::unlink(o.backup.c_str());
                if (::link(o.path.c_str(), o.backup.c_str()) != 0) {
                    const int err = errno;
                    o.backup.clear();
                    throw FileError(o.path, std::string("cannot keep the earlier file: ") +
                                                std::strerror(err));
                }
            }
            if (std::rename(o.temp.c_str(), o.path.c_str()) != 0) {
                throw FileError(o.path, std::string("rename failed: ") + std::strerror(errno));
            }
            o.temp.clear();
            o.replaced = true;
        }
    } catch (...) {
        roll_back();
        throw;
    }
    for (Output& o : outputs_) {
        if (!o.backup.empty()) ::unlink(o.backup.c_str());
        o.backup.clear();
    }
    committed_ = true;
}

void OutputTransaction::roll_back() noexcept {
    for (Output& o : outputs_) {
        if (!o.temp.empty()) ::unlink(o.temp.c_str());
        o.temp.clear();
        if (o.replaced) {
            if (!o.backup.empty()) {
                std::rename(o.backup.c_str(), o.path.c_str());
            } else {
                ::unlink(o.path.c_str());  // there was no file before the run
            }
        } else if (!o.backup.empty()) {
            ::unlink(o.backup.c_str());
        }
        o.backup.clear();
        o.replaced = false;
    }
}

}  // namespace stereoscene::support
