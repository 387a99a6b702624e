#include <catch2/catch.hpp>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include <unistd.h>

#include "stereoscene/support/asset_dir.hpp"
#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/error_line.hpp"

namespace fs = std::filesystem;
namespace support = stereoscene::support;

namespace {

std::string slurp(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

struct ScratchDir {
    fs::path path;
    ScratchDir() {
        path =
            fs::temp_directory_path() / ("stereoscene-support-" + std::to_string(::getpid()) + "-" +
                                         std::to_string(reinterpret_cast<std::uintptr_t>(this)));
        fs::create_directories(path);
    }
    ~ScratchDir() { fs::remove_all(path); }
};

/// Sets an environment variable for one scope and restores the old value after.
struct ScopedEnv {
    std::string name;
    std::optional<std::string> old;
    ScopedEnv(std::string n, const std::string& value) : name(std::move(n)) {
        if (const char* v = std::getenv(name.c_str())) old = v;
        ::setenv(name.c_str(), value.c_str(), 1);
    }
    ~ScopedEnv() {
        if (old) {
            ::setenv(name.c_str(), old->c_str(), 1);
        } else {
            ::unsetenv(name.c_str());
        }
    }
};

}  // namespace

TEST_CASE("an atomic write without fsync replaces the file whole and leaves no temp file",
          "[support]") {
    ScratchDir dir;
    const fs::path target = dir.path / "cloud.xyz";
    for (const auto sync : {support::FileSync::kDurable, support::FileSync::kAtomicOnly}) {
        support::write_file_atomic(target, "old contents\n", sync);
        CHECK(slurp(target) == "old contents\n");
        const std::string big(3 << 20, 'x');  // several write() calls
        support::write_file_atomic(target, big, sync);
        CHECK(slurp(target) == big);
    }
    CHECK_THROWS_AS(support::write_file_atomic(dir.path / "no-such-dir" / "c.xyz", "x",
                                               support::FileSync::kAtomicOnly),
                    support::FileError);
    std::size_t count = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path)) ++count;
    CHECK(count == 1);  // only cloud.xyz
}

TEST_CASE("an error line names the tool, then the file or flag, then the reason", "[support]") {
    CHECK(support::error_line("scene-render", "--size", "expected WxH, got '3'") ==
          "scene-render: error: --size: expected WxH, got '3'");
    CHECK(support::error_line("cloud-analysis", "", "out of memory") ==
          "cloud-analysis: error: out of memory");
    CHECK(support::error_line("t", "a\nb", "c\r\nd") == "t: error: a b: c  d");
}

TEST_CASE("a library error text becomes file or flag first, then what failed", "[support]") {
    CHECK(support::error_line("cloud-analysis", "cannot read image: no such file (/data/l.png)") ==
          "cloud-analysis: error: /data/l.png: cannot read image: no such file");
    CHECK(
        support::error_line("cloud-analysis", "cannot write output: no such folder (out, --ply)") ==
        "cloud-analysis: error: out, --ply: cannot write output: no such folder");
    // Parentheses inside the file name stay with it; a group inside the text is not a place.
    CHECK(support::split_where("bad value (x) in (a (1).txt)").where == "a (1).txt");
    CHECK(support::split_where("bad value (x) in (a (1).txt)").reason == "bad value (x) in");
    CHECK(support::split_where("no place here").where.empty());
    CHECK(support::split_where("unbalanced)").where.empty());
    CHECK(support::split_where("(only a group)").where.empty());
    CHECK(support::error_line("t", "two\nlines (f)\n") == "t: error: f: two lines");
    CHECK(support::error_line_of("t", "frame 7", "cannot read image: no such file (7.png)") ==
          "t: error: frame 7: 7.png: cannot read image: no such file");
    CHECK(support::error_line_of("t", "frame 7", "out of memory") ==
          "t: error: frame 7: out of memory");
}

TEST_CASE("the executable's folder is the one holding this test", "[support]") {
    const fs::path dir = support::executable_dir();
    REQUIRE_FALSE(dir.empty());
    CHECK(fs::exists(dir / "test_support"));
}

TEST_CASE("the assets folder comes from the environment first, else the tree", "[support]") {
    ::unsetenv(support::kAssetsEnv);
    // A build tree run in place: the source tree's assets (no install beside the tests).
    const fs::path found = support::asset_dir();
    CHECK(fs::equivalent(found, fs::path(STEREOSCENE_SOURCE_DIR) / "assets"));
    CHECK(fs::exists(found / "palettes" / "thesis.json"));

    ScratchDir dir;
    {
        ScopedEnv env(support::kAssetsEnv, dir.path.string());
        CHECK(support::asset_dir() == dir.path);
    }
    {
        ScopedEnv env(support::kAssetsEnv, (dir.path / "missing").string());
        try {
            support::asset_dir();
            FAIL("accepted a missing folder");
        } catch (const support::FileError& e) {
            const std::string what = e.what();
            CHECK(what.find((dir.path / "missing").string()) == 0);
            CHECK(what.find("STEREOSCENE_ASSETS") != std::string::npos);
        }
    }
}
