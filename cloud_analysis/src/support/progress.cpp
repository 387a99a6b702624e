#include "cloud_analysis/support/progress.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace cloud_analysis {

std::string format_duration(double seconds) {
    if (!(seconds >= 0.0) || seconds > 1e8) return "?";
    const auto s = static_cast<long long>(std::llround(seconds));
    char text[32];
    if (s >= 3600) {
        std::snprintf(text, sizeof text, "%lld:%02lld:%02lld", s / 3600, s / 60 % 60, s % 60);
    } else {
        std::snprintf(text, sizeof text, "%lld:%02lld", s / 60, s % 60);
    }
    return text;
}

std::string progress_text(const std::string& label, std::size_t done, std::size_t total,
                          std::size_t failed, double elapsed_s, bool bar) {
    std::string text = label + ": ";
    if (bar) {
        constexpr std::size_t kWidth = 24;
        const std::size_t filled = total == 0 ? kWidth : std::min(kWidth, done * kWidth / total);
        text += "[" + std::string(filled, '#') + std::string(kWidth - filled, ' ') + "] ";
    }
    const double fps = elapsed_s > 0.0 ? static_cast<double>(done) / elapsed_s : 0.0;
    char numbers[128];
    std::snprintf(numbers, sizeof numbers, "%zu/%zu frames, %.1f fps", done, total, fps);
    text += numbers;
    if (done < total) {
        text += ", ETA " + (fps > 0.0 ? format_duration(static_cast<double>(total - done) / fps)
                                      : std::string("?"));
    }
    text += ", " + std::to_string(failed) + " failed";
    return text;
}

void ProgressMeter::Options::validate() const {
    if (!(line_interval_s > 0.0)) throw std::invalid_argument("line_interval_s: must be > 0");
    if (!(redraw_interval_s >= 0.0)) {
        throw std::invalid_argument("redraw_interval_s: must be >= 0");
    }
}

ProgressMeter::ProgressMeter(std::string label, std::size_t total, Options options)
    : label_(std::move(label)), total_(total), options_(options) {
    options_.validate();
}

std::string ProgressMeter::update(std::size_t done, std::size_t failed, double elapsed_s) {
    if (finished_) return "";
    const bool last = done >= total_;
    const double interval =
        options_.terminal ? options_.redraw_interval_s : options_.line_interval_s;
    // Lines in a log are due every interval from the start; a terminal redraws at once.
    const double since =
        last_s_ < 0.0 ? (options_.terminal ? interval : elapsed_s) : elapsed_s - last_s_;
    if (!last && since < interval) return "";
    last_s_ = elapsed_s;
    finished_ = last;
    const std::string text =
        progress_text(label_, done, total_, failed, elapsed_s, options_.terminal);
    if (!options_.terminal) return text + "\n";
    // \r and clear to the end of line: the bar is redrawn in place; a newline after the last.
    return "\r" + text + "\x1b[K" + (last ? "\n" : "");
}

}  // namespace cloud_analysis
