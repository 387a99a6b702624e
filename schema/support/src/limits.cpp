#include "stereoscene/support/limits.hpp"

namespace stereoscene::support {
namespace {

Limits& current() {
    static Limits value;
    return value;
}

}  // namespace

const Limits& limits() { return current(); }

void set_limits(const Limits& limits) { current() = limits; }

void check_limit(const std::string& what, std::uint64_t count, std::uint64_t limit,
                 const std::string& unit, const std::string& hint) {
    if (count <= limit) return;
    std::string message = what + ": too large: " + std::to_string(count) + " " + unit +
                          " is more than the limit of " + std::to_string(limit);
    if (!hint.empty()) message += "; " + hint;
    throw LimitError(message);
}

}  // namespace stereoscene::support
