// Carries exceptions out of OpenMP regions, which they must not leave (std::terminate).
#pragma once

#include <atomic>
#include <exception>
#include <mutex>

namespace flashgs {

// Each body inside a parallel region runs through capture(); the first exception is kept,
// later bodies are skipped, and rethrow() after the region throws it on the calling thread.
// Nothing is allocated unless something throws.
class ParallelErrors {
 public:
  template <class Body>
  void capture(Body&& body) noexcept {
    if (m_failed.load(std::memory_order_relaxed)) return;
    try {
      body();
    } catch (...) {
      std::lock_guard<std::mutex> lock(m_mutex);
      if (!m_first) m_first = std::current_exception();
      m_failed.store(true, std::memory_order_relaxed);
    }
  }
  void rethrow() const {
    if (m_first) std::rethrow_exception(m_first);
  }

 private:
  std::atomic<bool> m_failed{false};
  std::mutex m_mutex;
  std::exception_ptr m_first;
};

}  // namespace flashgs
