#include "cloud_analysis/pipeline/frame_list.hpp"

#include <stdexcept>

namespace cloud_analysis {

std::string frame_id_problem(const std::string& frame) {
    if (frame.empty() || frame == "." || frame == "..") return "is not a file name";
    if (frame.size() > 200) return "is longer than 200 characters";
    for (const char c : frame) {
        if (c == '/' || c == '\\') return "holds a folder separator (outputs stay in --out-dir)";
        if (static_cast<unsigned char>(c) < 0x20) return "holds a control character";
    }
    return {};
}

std::vector<std::string> parse_frame_list(std::string_view text, const std::string& origin) {
    std::vector<std::string> frames;
    std::size_t number = 0;
    while (!text.empty()) {
        ++number;
        const std::size_t end = text.find('\n');
        std::string_view line = text.substr(0, end);
        text = end == std::string_view::npos ? std::string_view() : text.substr(end + 1);
        const auto first = line.find_first_not_of(" \t\r");
        if (first == std::string_view::npos || line[first] == '#') continue;
        const auto last = line.find_last_not_of(" \t\r");
        frames.emplace_back(line.substr(first, last - first + 1));
        if (const std::string problem = frame_id_problem(frames.back()); !problem.empty()) {
            throw std::runtime_error("bad frame list: line " + std::to_string(number) +
                                     ": frame id '" + frames.back() + "' " + problem + " (" +
                                     origin + ")");
        }
    }
    return frames;
}

}  // namespace cloud_analysis
