#pragma once
// A persistent second thread for two-way parallel loops, owned by the object that uses it (no
// global pool): starting a thread per parallel section costs about as much as a small section.

#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

namespace confluent {

// Runs fn(0) on the calling thread and fn(1) on a helper thread that is started on first use
// and kept until destruction; Run() returns when both are done. One caller at a time.
class HelperThread {
 public:
  HelperThread() = default;
  ~HelperThread();
  HelperThread(const HelperThread&) = delete;
  HelperThread& operator=(const HelperThread&) = delete;

  // Calls fn(0) here and fn(1) on the helper, concurrently; returns after both returned. fn
  // must not throw.
  void Run(const std::function<void(int)>& fn);

 private:
  void Loop();

  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable start_, finished_;
  const std::function<void(int)>* task_ = nullptr;
  long posted_ = 0, done_ = 0;  // tasks handed to and finished by the helper (guarded by mutex_)
  bool stop_ = false;
};

}  // namespace confluent
