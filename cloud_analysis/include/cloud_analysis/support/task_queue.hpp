#pragma once

/// Threads for the library's parallel parts: a pool kept between calls, a queue of tasks that
/// running tasks can add to, and a split of an index range into chunks.

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace cloud_analysis {

/// Threads kept between calls: starting a thread costs tens of microseconds, more right after
/// the matcher, and a call started three. Not OpenCV's pool: the task queue's workers block
/// while they wait for running tasks, which would starve a matcher running beside them on that
/// pool (batch mode). A call offers work to pool threads and runs it itself too, so it
/// completes even when no pool thread is free.
class ThreadPool {
  public:
    /// The process's pool (threads are started on first demand and joined at exit).
    static ThreadPool& instance();
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    /// Runs `fn` (which must not throw) on this thread and on up to `extra` pool threads at
    /// once; returns when every started copy has returned. Copies not started by the time this
    /// thread's copy returns are withdrawn.
    void run(int extra, const std::function<void()>& fn);

  private:
    struct Job {
        const std::function<void()>* fn;
        int running = 0;
    };
    ThreadPool() = default;
    ~ThreadPool();
    void serve();
    std::mutex mutex_;
    std::condition_variable wake_, done_;
    std::deque<Job*> offers_;
    std::vector<std::thread> threads_;
    bool stop_ = false;
};

/// Runs tasks on a fixed number of threads. A running task may add tasks at the front, to run
/// before the ones queued: a class's cluster fits start as soon as its clustering is done, on
/// whichever thread is free, so that no thread is left alone with the largest class at the
/// end. The first exception stops the run (queued tasks are dropped) and is rethrown by run().
class TaskQueue {
  public:
    using Task = std::function<void()>;
    /// Queues a task at the back; before run() or from a running task.
    void push_back(Task task);
    /// Queues tasks at the front, in their order.
    void push_front(std::vector<Task> tasks);
    /// Runs every task (those queued, and those they add) on `threads` threads, this one
    /// included; returns when all have run.
    void run(int threads);

  private:
    void work();
    std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<Task> queue_;
    int running_ = 0;
    std::exception_ptr failure_;
};

/// Calls body(c, first, last) for `chunks` contiguous ranges [first, last) of [0, n), taken in
/// turn by this thread and up to chunks - 1 pool threads; rethrows the first exception.
template <typename Body>
void for_each_chunk(std::size_t n, std::size_t chunks, Body&& body) {
    const auto bound = [&](std::size_t c) { return n / chunks * c + std::min(c, n % chunks); };
    std::atomic<std::size_t> next{0};
    std::mutex failure_mutex;
    std::exception_ptr failure;
    ThreadPool::instance().run(static_cast<int>(chunks) - 1, [&] {
        for (std::size_t c = next++; c < chunks; c = next++) {
            try {
                body(c, bound(c), bound(c + 1));
            } catch (...) {
                const std::lock_guard<std::mutex> lock(failure_mutex);
                if (!failure) failure = std::current_exception();
            }
        }
    });
    if (failure) std::rethrow_exception(failure);
}

}  // namespace cloud_analysis
