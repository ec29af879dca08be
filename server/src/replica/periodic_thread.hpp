#pragma once
// A thread that runs a task at once and then every interval until it is destroyed; the
// destructor wakes it from its wait and joins it.

#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

namespace pintag::replica {

class PeriodicThread {
 public:
  PeriodicThread() = default;
  ~PeriodicThread() { stop(); }
  PeriodicThread(const PeriodicThread&) = delete;
  PeriodicThread& operator=(const PeriodicThread&) = delete;

  /// Starts running `task` every `interval`; call once.
  void start(std::chrono::milliseconds interval, std::function<void()> task) {
    thread_ = std::thread([this, interval, task = std::move(task)] {
      while (true) {
        task();
        std::unique_lock lock(mutex_);
        if (stopping_changed_.wait_for(lock, interval, [this] { return stopping_; })) return;
      }
    });
  }

  /// Waits for a task in progress to finish and ends the thread.
  void stop() {
    {
      const std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    stopping_changed_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::mutex mutex_;
  std::condition_variable stopping_changed_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace pintag::replica
