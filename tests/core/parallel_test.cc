#include "core/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

namespace confluent {
namespace {

TEST(ParallelFor, RunsEveryIndexOnceOnSeveralThreads) {
  std::vector<std::atomic<int>> runs(100);
  std::vector<std::thread::id> threads(100);
  ParallelFor(100, 3, [&](int i) {
    ++runs[i];
    threads[i] = std::this_thread::get_id();
    std::this_thread::sleep_for(std::chrono::microseconds(200));  // lets the other threads take some
  });
  for (const std::atomic<int>& count : runs) EXPECT_EQ(count.load(), 1);
  std::vector<std::thread::id> distinct;
  for (const std::thread::id& id : threads)
    if (std::find(distinct.begin(), distinct.end(), id) == distinct.end()) distinct.push_back(id);
  EXPECT_GT(distinct.size(), 1u);
  EXPECT_LE(distinct.size(), 3u);
}

TEST(ParallelFor, RethrowsTheErrorOfAJobAndStopsHandingOutWork) {
  std::atomic<int> started{0};
  EXPECT_THROW(ParallelFor(1000, 2,
                           [&](int i) {
                             ++started;
                             if (i == 3) throw std::runtime_error("job 3 failed");
                             // A job that takes a while: instant jobs could all be handed out
                             // by the other thread before job 3's error is seen.
                             std::this_thread::sleep_for(std::chrono::microseconds(200));
                           }),
               std::runtime_error);
  EXPECT_LT(started.load(), 1000);
}

TEST(ParallelFor, NothingToDoAndOneThreadAreFine) {
  int calls = 0;
  ParallelFor(0, 2, [&](int) { ++calls; });
  EXPECT_EQ(calls, 0);
  std::vector<int> order;
  ParallelFor(4, 1, [&](int i) { order.push_back(i); });
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3}));
}

}  // namespace
}  // namespace confluent
