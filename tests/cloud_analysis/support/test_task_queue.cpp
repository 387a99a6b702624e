#include <atomic>
#include <mutex>
#include <stdexcept>
#include <vector>

#include <catch2/catch.hpp>

#include "cloud_analysis/support/task_queue.hpp"

using namespace cloud_analysis;

TEST_CASE("a task queue runs every task, those added by running tasks too", "[task_queue]") {
    for (const int threads : {1, 2, 4}) {
        TaskQueue queue;
        std::atomic<int> ran{0};
        for (int i = 0; i < 10; ++i) {
            queue.push_back([&] {
                ++ran;
                queue.push_front({[&] { ++ran; }, [&] { ++ran; }});
            });
        }
        queue.run(threads);
        CHECK(ran == 30);
    }
}

TEST_CASE("tasks added at the front run before the queued ones", "[task_queue]") {
    TaskQueue queue;
    std::mutex mutex;
    std::vector<int> order;
    const auto record = [&](int k) {
        const std::lock_guard<std::mutex> lock(mutex);
        order.push_back(k);
    };
    queue.push_back([&] {
        record(0);
        queue.push_front({[&] { record(1); }, [&] { record(2); }});
    });
    queue.push_back([&] { record(3); });
    queue.run(1);
    CHECK(order == std::vector<int>{0, 1, 2, 3});
}

TEST_CASE("the first exception of a task stops the queue and is rethrown", "[task_queue]") {
    TaskQueue queue;
    int after = 0;
    queue.push_back([] { throw std::runtime_error("task failed"); });
    queue.push_back([&] { ++after; });
    CHECK_THROWS_WITH(queue.run(1), "task failed");
    CHECK(after == 0);
}

TEST_CASE("chunks cover the range once, contiguous and in order", "[task_queue]") {
    for (const std::size_t chunks : {1, 2, 3, 7}) {
        std::vector<std::size_t> first(chunks), last(chunks);
        std::vector<int> seen(100, 0);
        for_each_chunk(seen.size(), chunks, [&](std::size_t c, std::size_t f, std::size_t l) {
            first[c] = f;
            last[c] = l;
            for (std::size_t i = f; i < l; ++i) ++seen[i];
        });
        CHECK(first.front() == 0);
        CHECK(last.back() == 100);
        for (std::size_t c = 1; c < chunks; ++c) CHECK(first[c] == last[c - 1]);
        for (int s : seen) CHECK(s == 1);
    }
}

TEST_CASE("an exception in a chunk is rethrown after every chunk ran", "[task_queue]") {
    std::atomic<int> ran{0};
    CHECK_THROWS_WITH(for_each_chunk(10, 3,
                                     [&](std::size_t c, std::size_t, std::size_t) {
                                         ++ran;
                                         if (c == 1) throw std::runtime_error("chunk failed");
                                     }),
                      "chunk failed");
    CHECK(ran == 3);
}
