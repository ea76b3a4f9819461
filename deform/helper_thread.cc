#include "deform/helper_thread.h"

namespace confluent {

HelperThread::~HelperThread() {
  if (!thread_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_.notify_one();
  thread_.join();
}

void HelperThread::Run(const std::function<void(int)>& fn) {
  if (!thread_.joinable()) thread_ = std::thread([this] { Loop(); });
  long ticket;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    task_ = &fn;
    ticket = ++posted_;
  }
  start_.notify_one();
  fn(0);
  std::unique_lock<std::mutex> lock(mutex_);
  finished_.wait(lock, [&] { return done_ == ticket; });
}

void HelperThread::Loop() {
  long seen = 0;
  for (;;) {
    const std::function<void(int)>* task;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_.wait(lock, [&] { return stop_ || posted_ != seen; });
      if (stop_) return;
      seen = posted_;
      task = task_;
    }
    (*task)(1);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = seen;
    }
    finished_.notify_one();
  }
}

}  // namespace confluent
