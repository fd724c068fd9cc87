// A fixed pool of std::thread workers created at set-up. run() hands every worker its index and
// waits for all of them; the caller's thread is worker 0. No allocation per run() (a function
// pointer and a context, no std::function); synchronisation is a mutex and two condition
// variables (futexes on Linux).
#pragma once

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace kestrel::sim {

class ThreadPool {
 public:
  using Task = void (*)(void* context, int worker);
  explicit ThreadPool(int num_threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;
  int size() const { return size_; }
  void run(Task task, void* context);

 private:
  void loop(int worker);
  int size_ = 1;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable start_cv_, done_cv_;
  std::uint64_t generation_ = 0;
  int remaining_ = 0;
  bool stop_ = false;
  Task task_ = nullptr;
  void* context_ = nullptr;
};

}  // namespace kestrel::sim
