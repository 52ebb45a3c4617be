// Host-side work split over the host's threads: the scene passes of the CUDA backend (packing
// for the upload, the bounds) are memory-bound, and one thread reaches a fraction of the
// host's bandwidth.
#pragma once

#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace flashgs {
namespace cuda {

// How many threads split `count` items: every hardware thread, but one per `min_items`.
inline unsigned host_threads_for(std::size_t count, std::size_t min_items) {
  return std::max(1u, std::min(std::thread::hardware_concurrency(), static_cast<unsigned>(count / min_items + 1)));
}

// Calls work(t, lo, hi) for t < threads on consecutive ranges covering [0, count), each on its
// own thread (t = 0 on the caller's), and returns when all have.
template <typename Work>
void for_each_host_range(std::size_t count, unsigned threads, const Work& work) {
  auto run = [&](unsigned t) { work(t, count * t / threads, count * (t + 1) / threads); };
  std::vector<std::thread> workers;
  for (unsigned t = 1; t < threads; ++t) workers.emplace_back(run, t);
  run(0);
  for (std::thread& w : workers) w.join();
}

}  // namespace cuda
}  // namespace flashgs
