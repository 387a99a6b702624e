#pragma once

/// The one-line error both tools print on stderr.

#include <string>
#include <string_view>

namespace stereoscene::support {

/// "<tool>: error: <where>: <reason>" (no newline), where `where` names the file or flag at
/// fault; an empty `where` gives "<tool>: error: <reason>". Line breaks inside the parts become
/// spaces, so the message stays one line.
std::string error_line(std::string_view tool, std::string_view where, std::string_view reason);

}  // namespace stereoscene::support
