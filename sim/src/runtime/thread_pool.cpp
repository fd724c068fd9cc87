#include "kestrel/sim/thread_pool.hpp"

namespace kestrel::sim {

ThreadPool::ThreadPool(int num_threads) : size_(num_threads < 1 ? 1 : num_threads) {
  threads_.reserve(static_cast<std::size_t>(size_ - 1));
  for (int w = 1; w < size_; ++w) threads_.emplace_back([this, w] { loop(w); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_cv_.notify_all();
  for (auto& t : threads_) t.join();
}

void ThreadPool::run(Task task, void* context) {
  if (size_ == 1) {
    task(context, 0);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    task_ = task;
    context_ = context;
    remaining_ = size_ - 1;
    ++generation_;
  }
  start_cv_.notify_all();
  task(context, 0);
  std::unique_lock<std::mutex> lock(mutex_);
  done_cv_.wait(lock, [this] { return remaining_ == 0; });
}

void ThreadPool::loop(int worker) {
  std::uint64_t seen = 0;
  for (;;) {
    Task task;
    void* context;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_cv_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      task = task_;
      context = context_;
    }
    task(context, worker);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --remaining_;
    }
    done_cv_.notify_one();
  }
}

}  // namespace kestrel::sim
