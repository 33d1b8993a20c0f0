#pragma once

#include <thread>
#include <vector>

namespace cblox {

/// Runs `work(thread_id)` on `num_threads` threads (ids 0..n-1; id 0 is the calling
/// thread) and returns when all are done. Exceptions must not escape `work`.
template <typename Work>
void runThreadTeam(int num_threads, Work&& work) {
  if (num_threads <= 1) {
    work(0);
    return;
  }
  std::vector<std::thread> threads;
  threads.reserve(static_cast<size_t>(num_threads - 1));
  for (int id = 1; id < num_threads; ++id) threads.emplace_back([&work, id] { work(id); });
  work(0);
  for (std::thread& thread : threads) thread.join();
}

}  // namespace cblox
