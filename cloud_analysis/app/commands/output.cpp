#include "output.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

namespace cloud_analysis::app {

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
