// LoadProgress: what a scene loader reports while it runs on its own thread (bytes, Gaussians), and the flag that asks it to stop.
#pragma once

#include <atomic>
#include <cstdint>

namespace flashgs {

// Written by the loader (relaxed atomics: the reader only shows them), read by the UI thread.
// A total of 0 means "not known yet".
struct LoadProgress {
  std::atomic<std::uint64_t> bytes_done{0};
  std::atomic<std::uint64_t> bytes_total{0};
  std::atomic<std::uint64_t> gaussians_done{0};
  std::atomic<std::uint64_t> gaussians_total{0};
  // Set by the UI; a loader that sees it throws flashgs::LoadCancelled at its next check.
  std::atomic<bool> cancel_requested{false};
};

}  // namespace flashgs
