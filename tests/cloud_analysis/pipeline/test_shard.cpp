#include <catch2/catch.hpp>

#include <map>
#include <string>
#include <vector>

#include "cloud_analysis/pipeline/shard.hpp"

using namespace cloud_analysis;

namespace {

std::vector<std::string> frame_list(int n) {
    std::vector<std::string> frames;
    for (int i = 0; i < n; ++i) frames.push_back("f" + std::to_string(i));
    return frames;
}

}  // namespace

TEST_CASE("N shards together do every frame exactly once, shares within one frame", "[shard]") {
    for (const int n : {0, 1, 2, 7, 100, 101}) {
        for (const int count : {1, 2, 3, 4, 10, 150}) {
            const auto frames = frame_list(n);
            std::map<std::string, int> seen;
            std::size_t smallest = frames.size(), largest = 0;
            for (int index = 0; index < count; ++index) {
                const auto share = shard_frames(frames, {index, count});
                smallest = std::min(smallest, share.size());
                largest = std::max(largest, share.size());
                for (const auto& f : share) ++seen[f];
            }
            CHECK(seen.size() == frames.size());
            for (const auto& [frame, times] : seen) CHECK(times == 1);
            CHECK(largest - smallest <= 1);
        }
    }
}

TEST_CASE("a shard is dealt round-robin, in list order, the same every time", "[shard]") {
    const auto frames = frame_list(10);
    CHECK(shard_frames(frames, {1, 3}) == std::vector<std::string>{"f1", "f4", "f7"});
    CHECK(shard_frames(frames, {0, 3}) == std::vector<std::string>{"f0", "f3", "f6", "f9"});
    CHECK(shard_frames(frames, {0, 1}) == frames);
    CHECK(shard_frames(frames, {2, 3}) == shard_frames(frames, {2, 3}));
}

TEST_CASE("a shard I/N parses, and bad values say what is wrong", "[shard]") {
    const Shard s = parse_shard("2/10");
    CHECK(s.index == 2);
    CHECK(s.count == 10);
    CHECK(parse_shard("0/1").count == 1);
    for (const char* bad :
         {"", "3", "3/", "/3", "a/3", "3/3", "4/3", "-1/3", "1/0", "1/3x", "1.5/3", " 1/3"}) {
        CAPTURE(bad);
        CHECK_THROWS_AS(parse_shard(bad), std::invalid_argument);
    }
    CHECK_THROWS_WITH(parse_shard("3/3"), Catch::Contains("0..2"));
}

TEST_CASE("a Slurm array task is a shard and without the variables the whole list", "[shard]") {
    const Shard whole = shard_from_slurm(nullptr, nullptr);
    CHECK(whole.index == 0);
    CHECK(whole.count == 1);
    const Shard task = shard_from_slurm("4", "5");
    CHECK(task.index == 4);
    CHECK(task.count == 5);
    CHECK_THROWS_AS(shard_from_slurm("4", nullptr), std::invalid_argument);
    CHECK_THROWS_AS(shard_from_slurm(nullptr, "5"), std::invalid_argument);
    // An array numbered 1..5 or a resubmitted subset (--array=7 of 10: count 1) is no shard.
    CHECK_THROWS_WITH(shard_from_slurm("5", "5"), Catch::Contains("--shard"));
    CHECK_THROWS_AS(shard_from_slurm("7", "1"), std::invalid_argument);
    CHECK_THROWS_AS(shard_from_slurm("x", "2"), std::invalid_argument);
}
