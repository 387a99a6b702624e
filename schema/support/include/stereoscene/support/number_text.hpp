#pragma once

/// Numbers as text for reports and messages.

#include <string>

namespace stereoscene::support {

/// `v` with `decimals` digits after the point, as printf's "%.*f" (C locale).
std::string fixed_text(double v, int decimals);

}  // namespace stereoscene::support
