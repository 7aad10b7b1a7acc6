#include "physics/step_pool.hpp"

#include <algorithm>

namespace uavsim::server::physics {

StepPool::StepPool(int threads) : threads_(std::max(threads, 1)) {
  workers_.reserve(static_cast<size_t>(threads_ - 1));
  for (int t = 1; t < threads_; ++t) workers_.emplace_back([this, t] { work(t); });
}

StepPool::~StepPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_cv_.notify_all();
  for (std::thread& w : workers_) w.join();
}

void StepPool::run(int tasks, const std::function<void(int)>& fn) {
  const int n = threads();
  if (n == 1 || tasks <= 1) {
    for (int t = 0; t < tasks; ++t) fn(t);
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    fn_ = &fn;
    tasks_ = tasks;
    busy_ = threads_ - 1;
    ++batch_;
  }
  start_cv_.notify_all();
  for (int t = 0; t < tasks; t += n) fn(t);
  std::unique_lock<std::mutex> lock(mutex_);
  done_cv_.wait(lock, [this] { return busy_ == 0; });
  fn_ = nullptr;
}

void StepPool::work(int thread) {
  uint64_t seen = 0;
  const int n = threads();
  for (;;) {
    const std::function<void(int)>* fn = nullptr;
    int tasks = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_cv_.wait(lock, [&] { return stop_ || batch_ != seen; });
      if (stop_) return;
      seen = batch_;
      fn = fn_;
      tasks = tasks_;
    }
    for (int t = thread; t < tasks; t += n) (*fn)(t);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (--busy_ == 0) done_cv_.notify_one();
    }
  }
}

}  // namespace uavsim::server::physics
