#include "stereoscene/support/file_read.hpp"

#include <cerrno>
#include <cstring>
#include <iostream>
#include <new>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/limits.hpp"

namespace stereoscene::support {
namespace {

const char* kind_of(mode_t mode) {
    if (S_ISDIR(mode)) return "a directory";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISSOCK(mode)) return "a socket";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    return "not a regular file";
}

[[noreturn]] void fail(const std::filesystem::path& path, const std::string& reason) {
    throw FileError(path, reason);
}

/// The flag that raises a byte limit, as "; <flag> raises it", or empty.
std::string byte_hint(std::uint64_t max_bytes) {
    if (max_bytes == limits().max_text_bytes) return "; --max-text-mib raises it";
    if (max_bytes == limits().max_file_bytes) return "; --max-file-mib raises it";
    return "";
}

void check_stat(const std::filesystem::path& path, const struct stat& st, std::uint64_t max_bytes) {
    if (!S_ISREG(st.st_mode)) {
        fail(path, std::string("not a regular file (") + kind_of(st.st_mode) + "), refused");
    }
    if (static_cast<std::uint64_t>(st.st_size) > max_bytes) {
        fail(path, "too large: " + std::to_string(st.st_size) +
                       " bytes is more than the limit of " + std::to_string(max_bytes) +
                       " bytes for this kind of file" + byte_hint(max_bytes));
    }
}

/// Reads up to max_bytes + 1 from fd, so a file that grew or a pipe that runs on is caught.
std::string read_all(int fd, const std::filesystem::path& path, std::uint64_t max_bytes,
                     std::size_t expected) {
    std::string out;
    out.reserve(expected);
    char chunk[1 << 16];
    for (;;) {
        const ssize_t n = ::read(fd, chunk, sizeof chunk);
        if (n < 0) {
            if (errno == EINTR) continue;
            fail(path, std::string("cannot read: ") + std::strerror(errno));
        }
        if (n == 0) break;
        out.append(chunk, static_cast<std::size_t>(n));
        if (out.size() > max_bytes) {
            fail(path, "too large: more than the limit of " + std::to_string(max_bytes) +
                           " bytes for this kind of file" + byte_hint(max_bytes));
        }
    }
    return out;
}

/// Standard input through std::cin (which a caller may have redirected), up to max_bytes.
std::string read_stdin(std::uint64_t max_bytes) {
    std::string out;
    char chunk[1 << 16];
    while (std::cin.read(chunk, sizeof chunk) || std::cin.gcount() > 0) {
        out.append(chunk, static_cast<std::size_t>(std::cin.gcount()));
        if (out.size() > max_bytes) {
            fail("-", "standard input is more than the limit of " + std::to_string(max_bytes) +
                          " bytes for this kind of file");
        }
    }
    if (std::cin.bad()) fail("-", "cannot read standard input");
    return out;
}

}  // namespace

void check_input_file(const std::filesystem::path& path, std::uint64_t max_bytes) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        fail(path, std::string("cannot open: ") + std::strerror(errno));
    }
    check_stat(path, st, max_bytes);
}

std::string read_file_bounded(const std::filesystem::path& path, std::uint64_t max_bytes) {
    if (path == "-") return read_stdin(max_bytes);
    // O_NONBLOCK: opening a FIFO without a writer returns at once instead of waiting.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) fail(path, std::string("cannot open: ") + std::strerror(errno));
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    struct stat st {};
    if (::fstat(fd, &st) != 0) fail(path, std::string("cannot stat: ") + std::strerror(errno));
    check_stat(path, st, max_bytes);
    try {
        return read_all(fd, path, max_bytes, static_cast<std::size_t>(st.st_size));
    } catch (const std::bad_alloc&) {
        fail(path, "out of memory reading its " + std::to_string(st.st_size) + " bytes");
    }
}

std::vector<unsigned char> read_file_bytes_bounded(const std::filesystem::path& path,
                                                   std::uint64_t max_bytes) {
    const std::string text = read_file_bounded(path, max_bytes);
    try {
        return std::vector<unsigned char>(text.begin(), text.end());
    } catch (const std::bad_alloc&) {
        fail(path, "out of memory holding its " + std::to_string(text.size()) + " bytes");
    }
}

std::string read_text_input(const std::filesystem::path& path) {
    return read_file_bounded(path, limits().max_text_bytes);
}

std::vector<unsigned char> read_binary_input(const std::filesystem::path& path) {
    return read_file_bytes_bounded(path, limits().max_file_bytes);
}

}  // namespace stereoscene::support
