#pragma once
// Work spread over a few threads.

#include <functional>

namespace confluent {

// Runs job(i) for i in [0, count) on up to `threads` threads (the calling thread is one of them);
// stops handing out work after the first error and rethrows it.
void ParallelFor(int count, int threads, const std::function<void(int)>& job);

}  // namespace confluent
