#pragma once

/// Frame ids for batch: read from a list file and checked to name files inside the output
/// folder only.

#include <string>
#include <string_view>
#include <vector>

namespace cloud_analysis {

/// Why a frame id cannot name files inside the output folder, or empty when it can: an id is
/// one plain file name (no folder separators, not "." or "..", no control characters, at most
/// 200 characters).
std::string frame_id_problem(const std::string& frame);

/// The frame ids of a list, one a line; blank lines and lines starting with '#' are skipped,
/// surrounding white space is trimmed. Throws std::runtime_error
/// "bad frame list: line N: frame id '<id>' <problem> (<origin>)" for an id that
/// frame_id_problem() refuses.
std::vector<std::string> parse_frame_list(std::string_view text, const std::string& origin);

}  // namespace cloud_analysis
