#include "output.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace cloud_analysis::app {

void require_input_files(const std::vector<std::filesystem::path>& inputs,
                         std::string_view action) {
    for (const auto& f : inputs) {
        if (f.empty() || f == "-") continue;
        std::error_code ec;
        if (!std::filesystem::is_regular_file(f, ec)) {
            throw std::runtime_error(
                "cannot " + std::string(action) + ": " +
                (std::filesystem::exists(f, ec) ? "not a regular file" : "no such file") + " (" +
                f.string() + ")");
        }
    }
}

void write_output(const PendingOutput& out) {
    if (out.path == "-") {
        // SIGPIPE is ignored (main): a reader that went away is an error line, not a signal.
        if (std::fwrite(out.bytes.data(), 1, out.bytes.size(), stdout) != out.bytes.size() ||
            std::fflush(stdout) != 0) {
            throw std::runtime_error(std::string("cannot write output: standard output: ") +
                                     std::strerror(errno) + " (-)");
        }
    } else {
        stereoscene::support::write_file_atomic(out.path, out.bytes, out.sync);
    }
}

}  // namespace cloud_analysis::app
