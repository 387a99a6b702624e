#include <catch2/catch.hpp>

#include <string>

#include "cloud_analysis/support/progress.hpp"

using namespace cloud_analysis;

TEST_CASE("durations read m:ss, then h:mm:ss", "[progress]") {
    CHECK(format_duration(0.0) == "0:00");
    CHECK(format_duration(7.4) == "0:07");
    CHECK(format_duration(754.0) == "12:34");
    CHECK(format_duration(3723.0) == "1:02:03");
    CHECK(format_duration(-1.0) == "?");
}

TEST_CASE("progress text gives frames, rate, ETA and failures", "[progress]") {
    CHECK(progress_text("batch", 50, 200, 1, 10.0, false) ==
          "batch: 50/200 frames, 5.0 fps, ETA 0:30, 1 failed");
    CHECK(progress_text("batch", 0, 200, 0, 0.0, false) ==
          "batch: 0/200 frames, 0.0 fps, ETA ?, 0 failed");
    CHECK(progress_text("batch", 200, 200, 0, 40.0, false) ==
          "batch: 200/200 frames, 5.0 fps, 0 failed");
    CHECK(progress_text("b", 12, 24, 0, 6.0, true) ==
          "b: [############            ] 12/24 frames, 2.0 fps, ETA 0:06, 0 failed");
}

TEST_CASE("in a log a line is due every interval and at the end, once", "[progress]") {
    ProgressMeter::Options options;
    options.line_interval_s = 10.0;
    ProgressMeter meter("batch", 100, options);
    CHECK(meter.update(1, 0, 0.5) == "");
    CHECK(meter.update(5, 0, 9.9) == "");
    const std::string line = meter.update(11, 0, 10.1);
    CHECK(line == "batch: 11/100 frames, 1.1 fps, ETA 1:22, 0 failed\n");
    CHECK(meter.update(12, 0, 15.0) == "");
    CHECK(meter.update(30, 0, 20.2) != "");
    CHECK(meter.update(100, 2, 21.0) == "batch: 100/100 frames, 4.8 fps, 2 failed\n");
    CHECK(meter.update(100, 2, 40.0) == "");
}

TEST_CASE("on a terminal the bar is redrawn in place, at most every redraw interval",
          "[progress]") {
    ProgressMeter::Options options;
    options.terminal = true;
    options.redraw_interval_s = 0.2;
    ProgressMeter meter("b", 4, options);
    const std::string first = meter.update(1, 0, 0.05);
    CHECK(first.rfind("\rb: [######", 0) == 0);
    CHECK(first.find('\n') == std::string::npos);
    CHECK(meter.update(2, 0, 0.1) == "");
    CHECK(meter.update(3, 0, 0.3) != "");
    const std::string last = meter.update(4, 0, 0.35);
    CHECK(last.back() == '\n');
    ProgressMeter::Options bad;
    bad.line_interval_s = 0.0;
    CHECK_THROWS_AS(ProgressMeter("b", 1, bad), std::invalid_argument);
}
