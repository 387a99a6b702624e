#include "stereoscene/support/error_line.hpp"

namespace stereoscene::support {
namespace {

void append_one_line(std::string& out, std::string_view text) {
    for (const char c : text) out += (c == '\n' || c == '\r') ? ' ' : c;
}

}  // namespace

std::string error_line(std::string_view tool, std::string_view where, std::string_view reason) {
    std::string out(tool);
    out += ": error: ";
    if (!where.empty()) {
        append_one_line(out, where);
        out += ": ";
    }
    append_one_line(out, reason);
    return out;
}

}  // namespace stereoscene::support
