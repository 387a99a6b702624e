#pragma once

/// The one-line error both tools print on stderr.

#include <string>
#include <string_view>

namespace stereoscene::support {

/// "<tool>: error: <where>: <reason>" (no newline), where `where` names the file or flag at
/// fault; an empty `where` gives "<tool>: error: <reason>". Line breaks inside the parts become
/// spaces, so the message stays one line.
std::string error_line(std::string_view tool, std::string_view where, std::string_view reason);

/// An exception text of the libraries' form "<what failed>: <detail> (<file or flag>)" split
/// into {where, reason}: the last parenthesised group at the end of the text is `where`, the rest
/// is `reason`. A text without that group has an empty `where`.
struct WhereReason {
    std::string where;
    std::string reason;
};
WhereReason split_where(std::string_view message);

/// error_line() of a library exception text: "<tool>: error: <file or flag>: <what>: <detail>".
std::string error_line(std::string_view tool, std::string_view message);

/// The same for one item of many (e.g. "frame 000004_10"): "<tool>: error: <item>: <file or
/// flag>: <what>: <detail>".
std::string error_line_of(std::string_view tool, std::string_view item, std::string_view message);

}  // namespace stereoscene::support
