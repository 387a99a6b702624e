#include <catch2/catch.hpp>

#include <string>
#include <vector>

#include "cloud_analysis/pipeline/frame_list.hpp"

using cloud_analysis::frame_id_problem;
using cloud_analysis::parse_frame_list;

TEST_CASE("a frame list skips comments and blank lines and trims each id", "[batch]") {
    const std::vector<std::string> frames =
        parse_frame_list("# KITTI\n000000_10\n\n  000001_10 \r\n#000002_10\n000003_10", "l.txt");
    CHECK(frames == std::vector<std::string>{"000000_10", "000001_10", "000003_10"});
}

TEST_CASE("frame ids that would write outside the output folder are refused", "[batch]") {
    CHECK(frame_id_problem("000000_10").empty());
    CHECK(frame_id_problem("left.v2").empty());
    const std::vector<std::string> bad_ids = {
        "", ".", "..", "../x", "/tmp/x", "a/b", "a\\b", "a\nb", std::string(201, 'a')};
    for (const std::string& bad : bad_ids) {
        CHECK_FALSE(frame_id_problem(bad).empty());
    }
    CHECK_THROWS_WITH(parse_frame_list("000000_10\n../escape\n", "l.txt, --list"),
                      "bad frame list: line 2: frame id '../escape' holds a folder separator "
                      "(outputs stay in --out-dir) (l.txt, --list)");
}
