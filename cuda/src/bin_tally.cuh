// Pairs per bin counted by the kernels that emit them, for bin-sort frames
// (FrameBuffers::emitted_bin_counts): each block counts its pairs in shared memory and adds
// its non-zero counts to the frame's once, so that no counting pass reads the pairs again.
// A global atomic per pair would meet on the same words (a warp's pairs go to a few bins,
// docs/PERFORMANCE.md); shared counts meet only within the block.
#pragma once

#include <cstdint>

#include "pipeline.h"

namespace flashgs {
namespace cuda {

// The counts live in the kernel's dynamic shared memory. PACKED: two 16-bit counts per word,
// bins [0, half) in the low halves and [half, 2 half) in the high ones, half = (bins + 1) / 2
// (neighbouring bins in neighbouring words, so lanes storing a row of bins do not meet on a
// word), for a kernel whose shared memory is tight; a block may then add at most 65,535 pairs
// to a bin. Otherwise a word per bin. Everything is read from the kernel's
// FrameBuffers parameter, so that no register holds the tally across the emission code. A
// kernel of a frame that does not count takes NoBinTally instead: the same code, no counts.
template <bool PACKED>
struct BinTally {
  __device__ static unsigned* words() {
    extern __shared__ unsigned bin_tally_words[];
    return bin_tally_words;
  }
  __device__ static unsigned word_count(const FrameBuffers& buf) {
    const unsigned bins = static_cast<unsigned>(buf.bins.x) * static_cast<unsigned>(buf.bins.y);
    return PACKED ? (bins + 1) / 2 : bins;
  }

  // Every thread of the block calls; a barrier must follow before the first add.
  __device__ static void clear(const FrameBuffers& buf) {
    for (unsigned w = threadIdx.x; w < word_count(buf); w += blockDim.x) words()[w] = 0;
  }

  __device__ static __forceinline__ void add(const FrameBuffers& buf, unsigned bin) {
    if (!PACKED) {
      atomicAdd(words() + bin, 1u);
    } else {
      const bool high = bin >= word_count(buf);
      atomicAdd(words() + (high ? bin - word_count(buf) : bin), high ? 1u << 16 : 1u);
    }
  }

  // Adds the block's counts to the frame's and clears them for more adds. Every thread of the
  // block calls, after a barrier that follows its last add; a barrier must follow before the
  // next add.
  __device__ static void flush(const FrameBuffers& buf) {
    const unsigned half = word_count(buf);
    for (unsigned w = threadIdx.x; w < half; w += blockDim.x) {
      const unsigned v = words()[w];
      if (v == 0) continue;
      words()[w] = 0;
      if (!PACKED) {
        atomicAdd(buf.emitted_bin_counts + w, v);
      } else {
        if (v & 0xffffu) atomicAdd(buf.emitted_bin_counts + w, v & 0xffffu);
        if (v >> 16) atomicAdd(buf.emitted_bin_counts + half + w, v >> 16);
      }
    }
  }

  // Shared memory bytes a block needs for `bins` bins.
  static std::size_t bytes(unsigned bins) {
    return static_cast<std::size_t>(PACKED ? (bins + 1) / 2 : bins) * sizeof(unsigned);
  }
};

struct NoBinTally {
  __device__ static void clear(const FrameBuffers&) {}
  __device__ static void add(const FrameBuffers&, unsigned) {}
  __device__ static void flush(const FrameBuffers&) {}
  static std::size_t bytes(unsigned) { return 0; }
};

}  // namespace cuda
}  // namespace flashgs
