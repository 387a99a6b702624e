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

WhereReason split_where(std::string_view message) {
    // Trailing white space (a library text may end with a line break) is not part of it.
    while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) {
        message.remove_suffix(1);
    }
    if (message.size() < 2 || message.back() != ')') return {"", std::string(message)};
    // The group that closes the text: match parentheses backwards (paths may hold some).
    int depth = 0;
    for (std::size_t i = message.size(); i-- > 0;) {
        if (message[i] == ')') ++depth;
        if (message[i] == '(' && --depth == 0) {
            if (i == 0 || message[i - 1] != ' ' || i + 2 >= message.size()) break;
            return {std::string(message.substr(i + 1, message.size() - i - 2)),
                    std::string(message.substr(0, i - 1))};
        }
    }
    return {"", std::string(message)};
}

std::string error_line(std::string_view tool, std::string_view message) {
    const WhereReason parts = split_where(message);
    return error_line(tool, parts.where, parts.reason);
}

std::string error_line_of(std::string_view tool, std::string_view item, std::string_view message) {
    const WhereReason parts = split_where(message);
    std::string where(item);
    if (!parts.where.empty()) where += ": " + parts.where;
    return error_line(tool, where, parts.reason);
}

}  // namespace stereoscene::support
