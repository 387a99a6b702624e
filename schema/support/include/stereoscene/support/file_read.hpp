#pragma once

/// Reading outside files whole, without hanging on a FIFO or a device and without reading more
/// than a bound: the one way both tools read the files they are given.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace stereoscene::support {

/// Throws FileError "<path>: <reason>" unless `path` is a regular file (after symbolic links)
/// of at most `max_bytes`: directories, FIFOs, sockets and devices are refused without being
/// opened for reading, so a FIFO without a writer cannot block and /dev/zero cannot fill memory.
/// For libraries that open the file themselves.
void check_input_file(const std::filesystem::path& path, std::uint64_t max_bytes);

/// The whole content of a regular file of at most `max_bytes`, checked as by
/// check_input_file() on the open descriptor (no race with a file swapped in between). "-"
/// reads standard input, which may be a pipe, up to the same bound. Throws FileError
/// "<path>: <reason>".
std::string read_file_bounded(const std::filesystem::path& path, std::uint64_t max_bytes);

/// The same as bytes.
std::vector<unsigned char> read_file_bytes_bounded(const std::filesystem::path& path,
                                                   std::uint64_t max_bytes);

/// A text input (calibration, entity file, palette, class table, rig, list) under
/// limits().max_text_bytes.
std::string read_text_input(const std::filesystem::path& path);

/// A binary input (image, model, cloud) under limits().max_file_bytes.
std::vector<unsigned char> read_binary_input(const std::filesystem::path& path);

}  // namespace stereoscene::support
