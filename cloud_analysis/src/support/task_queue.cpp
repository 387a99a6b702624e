#include "cloud_analysis/support/task_queue.hpp"

#include <utility>

namespace cloud_analysis {

ThreadPool& ThreadPool::instance() {
    static ThreadPool pool;
    return pool;
}

void ThreadPool::run(int extra, const std::function<void()>& fn) {
    Job job{&fn};
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        while (static_cast<int>(threads_.size()) < extra) {
            threads_.emplace_back([this] { serve(); });
        }
        for (int i = 0; i < extra; ++i) offers_.push_back(&job);
    }
    wake_.notify_all();
    fn();
    std::unique_lock<std::mutex> lock(mutex_);
    offers_.erase(std::remove(offers_.begin(), offers_.end(), &job), offers_.end());
    done_.wait(lock, [&job] { return job.running == 0; });
}

ThreadPool::~ThreadPool() {
    {
        const std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : threads_) t.join();
}

void ThreadPool::serve() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
        wake_.wait(lock, [this] { return stop_ || !offers_.empty(); });
        if (stop_) return;
        Job* job = offers_.front();
        offers_.pop_front();
        ++job->running;
        lock.unlock();
        (*job->fn)();
        lock.lock();
        --job->running;
        done_.notify_all();
    }
}

void TaskQueue::push_back(Task task) {
    const std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(task));
    wake_.notify_one();
}

void TaskQueue::push_front(std::vector<Task> tasks) {
    const std::lock_guard<std::mutex> lock(mutex_);
    queue_.insert(queue_.begin(), std::make_move_iterator(tasks.begin()),
                  std::make_move_iterator(tasks.end()));
    wake_.notify_all();
}

void TaskQueue::run(int threads) {
    ThreadPool::instance().run(threads - 1, [this] { work(); });
    if (failure_) std::rethrow_exception(failure_);
}

void TaskQueue::work() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
        wake_.wait(lock, [this] { return !queue_.empty() || running_ == 0; });
        if (queue_.empty()) return;  // and nothing running that could add more
        Task task = std::move(queue_.front());
        queue_.pop_front();
        ++running_;
        lock.unlock();
        std::exception_ptr failure;
        try {
            task();
        } catch (...) {
            failure = std::current_exception();
        }
        lock.lock();
        --running_;
        if (failure) {
            if (!failure_) failure_ = failure;
            queue_.clear();
        }
        if (queue_.empty() && running_ == 0) wake_.notify_all();
    }
}

}  // namespace cloud_analysis
