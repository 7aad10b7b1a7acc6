// A small fixed pool of threads that runs a batch of independent tasks and waits for all of them:
// the physics shards' lockstep (physics/world.hpp). Task t always runs on thread t mod threads()
// (the caller is thread 0), so which thread runs a task is fixed, and tasks that share no state
// give the same results for any thread count.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace uavsim::server::physics {

class StepPool {
 public:
  // threads >= 1: the caller and threads - 1 workers (clamped to at least 1).
  explicit StepPool(int threads);
  ~StepPool();
  StepPool(const StepPool&) = delete;
  StepPool& operator=(const StepPool&) = delete;

  int threads() const { return threads_; }
  // Runs fn(0) .. fn(tasks - 1), task t on thread t mod threads(), and returns when every task has
  // run. fn must not throw. One caller at a time (the loop thread).
  void run(int tasks, const std::function<void(int)>& fn);

 private:
  void work(int thread);

  const int threads_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable start_cv_, done_cv_;
  const std::function<void(int)>* fn_ = nullptr;  // the batch in progress, guarded by mutex_
  int tasks_ = 0;
  uint64_t batch_ = 0;  // bumped per batch
  int busy_ = 0;        // workers still running the batch
  bool stop_ = false;
};

}  // namespace uavsim::server::physics
