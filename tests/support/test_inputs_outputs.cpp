#include <catch2/catch.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "stereoscene/support/atomic_file.hpp"
#include "stereoscene/support/file_read.hpp"
#include "stereoscene/support/folder_lock.hpp"
#include "stereoscene/support/limits.hpp"
#include "stereoscene/support/output_transaction.hpp"

namespace fs = std::filesystem;
namespace support = stereoscene::support;

namespace {

struct Scratch {
    fs::path path;
    Scratch() {
        path = fs::temp_directory_path() / ("stereoscene-io-" + std::to_string(::getpid()) + "-" +
                                            std::to_string(reinterpret_cast<std::uintptr_t>(this)));
        fs::create_directories(path);
    }
    ~Scratch() { fs::remove_all(path); }
};

void put(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

std::string get(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

std::size_t entries(const fs::path& dir) {
    std::size_t n = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
    return n;
}

}  // namespace

TEST_CASE("the bounded reader reads a regular file whole", "[support]") {
    Scratch s;
    put(s.path / "a.txt", "hello");
    CHECK(support::read_file_bounded(s.path / "a.txt", 5) == "hello");
    CHECK_THROWS_WITH(support::read_file_bounded(s.path / "a.txt", 4),
                      Catch::Contains("a.txt") && Catch::Contains("limit of 4 bytes"));
    CHECK_THROWS_WITH(support::read_file_bounded(s.path / "missing", 4),
                      Catch::Contains("missing: cannot open"));
}

TEST_CASE("the bounded reader refuses FIFOs, devices and directories without blocking",
          "[support]") {
    Scratch s;
    const fs::path fifo = s.path / "fifo";
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    CHECK_THROWS_WITH(support::read_file_bounded(fifo, 1 << 20), Catch::Contains("a FIFO"));
    CHECK_THROWS_WITH(support::check_input_file(fifo, 1 << 20), Catch::Contains("a FIFO"));
    CHECK_THROWS_WITH(support::read_file_bounded("/dev/zero", 1 << 20),
                      Catch::Contains("a character device"));
    CHECK_THROWS_WITH(support::read_file_bounded(s.path, 1 << 20), Catch::Contains("a directory"));
    try {
        support::read_file_bounded(fifo, 1);
    } catch (const support::FileError& e) {
        CHECK(e.path() == fifo);
        CHECK(e.reason().find(fifo.string()) == std::string::npos);
    }
}

TEST_CASE("a limit names the input, the count and the limit", "[support]") {
    CHECK_NOTHROW(support::check_limit("x.png", 10, 10, "pixels"));
    CHECK_THROWS_AS(support::check_limit("x.png", 11, 10, "pixels"), support::LimitError);
    CHECK_THROWS_WITH(support::check_limit("x.png", 11, 10, "pixels", "--max-pixels"),
                      "x.png: too large: 11 pixels is more than the limit of 10; --max-pixels");
}

TEST_CASE("running out of memory is named after what was being read", "[support]") {
    CHECK(support::name_out_of_memory("x.png", [] { return 3; }) == 3);
    CHECK_THROWS_WITH(
        support::name_out_of_memory("x.png: decoding", []() -> int { throw std::bad_alloc(); }),
        Catch::StartsWith("x.png: decoding: out of memory"));
    CHECK_THROWS_AS(support::name_out_of_memory("x", []() -> int { throw std::bad_alloc(); }),
                    support::LimitError);
}

TEST_CASE("an atomic write refuses a directory at the target instead of swapping it aside",
          "[support]") {
    Scratch s;
    fs::create_directory(s.path / "out.json");
    put(s.path / "out.json" / "keep", "x");
    for (auto sync : {support::FileSync::kDurable, support::FileSync::kAtomicOnly}) {
        CHECK_THROWS_WITH(support::write_file_atomic(s.path / "out.json", "{}", sync),
                          Catch::Contains("is a directory"));
    }
    CHECK(get(s.path / "out.json" / "keep") == "x");
    CHECK(entries(s.path) == 1);
}

TEST_CASE("an output transaction writes every file or none", "[support]") {
    Scratch s;
    const fs::path a = s.path / "a.png", b = s.path / "b.glb";
    {
        support::OutputTransaction t;
        t.declare(a, "-o");
        t.declare(b, "--glb");
        t.stage(a, "A");
        t.stage(b, "B");
        CHECK_FALSE(fs::exists(a));
        t.commit();
    }
    CHECK(get(a) == "A");
    CHECK(get(b) == "B");
    CHECK(entries(s.path) == 2);
    {
        support::OutputTransaction t;
        t.stage(a, "A2");
        // Dropped before the commit (an error in a later stage): nothing changes.
    }
    CHECK(get(a) == "A");
    CHECK(entries(s.path) == 2);
}

TEST_CASE("a failed commit restores the earlier files instead of removing them", "[support]") {
    Scratch s;
    const fs::path a = s.path / "a.png", b = s.path / "b.glb", c = s.path / "c.json";
    put(a, "old A");
    support::OutputTransaction t;
    t.stage(a, "new A");
    t.stage(c, "new C");
    t.stage(b, "new B");
    // A directory appears at b's path after staging: its rename fails during the commit.
    fs::create_directory(b);
    CHECK_THROWS_WITH(t.commit(), Catch::Contains("b.glb"));
    CHECK(get(a) == "old A");
    CHECK_FALSE(fs::exists(c));
    CHECK(fs::is_directory(b));
    CHECK(entries(s.path) == 2);  // a.png and the directory: no temp file, no backup
}

TEST_CASE("an output transaction refuses a directory and a path named twice up front",
          "[support]") {
    Scratch s;
    fs::create_directory(s.path / "dir");
    support::OutputTransaction t;
    CHECK_THROWS_WITH(t.declare(s.path / "dir", "-o"), Catch::Contains("is a directory"));
    t.declare(s.path / "x.png", "-o");
    CHECK_THROWS_WITH(t.declare(s.path / "dir" / ".." / "x.png", "--glb"),
                      Catch::Contains("--glb is the same file as -o"));
    CHECK_THROWS_WITH(support::check_output_path(s.path / "no" / "x.png"),
                      Catch::Contains("no such folder"));
    CHECK_NOTHROW(support::check_output_path("-"));
}

TEST_CASE("a folder lock keeps a second writer out until it is released, then is taken over",
          "[support][lock]") {
    Scratch s;
    {
        const support::FolderLock first(s.path, ".lock");
        CHECK(fs::exists(s.path / ".lock"));
        std::ifstream pid_file(s.path / ".lock");
        long pid = 0;
        pid_file >> pid;
        CHECK(pid == ::getpid());
        CHECK_THROWS_WITH(support::FolderLock(s.path, ".lock"),
                          Catch::Contains(".lock: held by another writer (pid " +
                                          std::to_string(::getpid()) + ")"));
        // Another name is another lock.
        const support::FolderLock other(s.path, ".other.lock");
    }
    CHECK_FALSE(fs::exists(s.path / ".lock"));     // removed on release
    std::ofstream(s.path / ".lock") << "99999\n";  // as a writer that died leaves it
    const support::FolderLock again(s.path, ".lock");
    CHECK_THROWS_WITH(support::FolderLock(s.path / "missing", ".lock"),
                      Catch::Contains("cannot lock"));
}
