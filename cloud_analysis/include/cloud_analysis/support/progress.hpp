#pragma once

/// Progress text for long runs: on a terminal a bar redrawn in place with frames/s and ETA, in
/// a log (a Slurm job's output file) a plain line every few seconds. Builds text only; the
/// caller prints it (to stderr).

#include <cstddef>
#include <string>

namespace cloud_analysis {

/// "0:07", "12:34", "1:02:03" (h:mm:ss from one hour on); "?" for a negative or huge value.
std::string format_duration(double seconds);

/// "<label>: 37/200 frames, 12.3 fps, ETA 0:13, 1 failed", with a 24-character bar
/// "[#####...   ]" after the label when `bar`. The rate is done / elapsed; no ETA before the
/// first frame.
std::string progress_text(const std::string& label, std::size_t done, std::size_t total,
                          std::size_t failed, double elapsed_s, bool bar);

/// Decides when progress is due and gives the text to print.
class ProgressMeter {
  public:
    struct Options {
        bool terminal = false;           ///< redraw a bar in place (\r) instead of printing lines
        double line_interval_s = 10.0;   ///< not a terminal: seconds between lines
        double redraw_interval_s = 0.2;  ///< terminal: least seconds between redraws
        void validate() const;           ///< throws std::invalid_argument naming the field
    };

    ProgressMeter(std::string label, std::size_t total, Options options);

    /// The text to print for `done` frames at `elapsed_s` seconds since the start, or "" when
    /// none is due. The last frame (done == total) is always due, once.
    std::string update(std::size_t done, std::size_t failed, double elapsed_s);

  private:
    std::string label_;
    std::size_t total_;
    Options options_;
    double last_s_ = -1.0;  ///< when text was last given, s; < 0 = never
    bool finished_ = false;
};

}  // namespace cloud_analysis
