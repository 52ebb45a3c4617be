// Frame memory estimates and the memory available to this process (see frame_memory.h).
#include "flashgs/frame_memory.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <fstream>
#include <sstream>

#include "cpu_frame.h"

namespace flashgs {
namespace {

// One value of a /proc or /sys file's first token; false when absent or not a number.
bool read_first_number(const std::string& path, std::uint64_t* value) {
  std::ifstream in(path);
  unsigned long long v = 0;
  if (!(in >> v)) return false;
  *value = v;
  return true;
}

bool read_mem_available(std::uint64_t* bytes) {
  std::ifstream in("/proc/meminfo");
  std::string key;
  unsigned long long kb = 0;
  std::string unit;
  while (in >> key >> kb >> unit)
    if (key == "MemAvailable:") {
      *bytes = static_cast<std::uint64_t>(kb) * 1024;
      return true;
    }
  return false;
}

bool read_address_space_left(std::uint64_t* bytes) {
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return false;
  std::uint64_t pages = 0;
  if (!read_first_number("/proc/self/statm", &pages)) return false;
  const std::uint64_t mapped = pages * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
  *bytes = limit.rlim_cur > mapped ? limit.rlim_cur - mapped : 0;
  return true;
}

bool read_cgroup_left(std::uint64_t* bytes) {
  // cgroup v2: "0::/path" in /proc/self/cgroup names this process's group.
  std::ifstream in("/proc/self/cgroup");
  std::string line, group = "/";
  while (std::getline(in, line))
    if (line.rfind("0::", 0) == 0) group = line.substr(3);
  const std::string dir = "/sys/fs/cgroup" + (group == "/" ? std::string() : group);
  std::uint64_t max = 0, current = 0;
  if (!read_first_number(dir + "/memory.max", &max) || !read_first_number(dir + "/memory.current", &current))
    return false;  // "max" (no limit) does not parse as a number
  *bytes = max > current ? max - current : 0;
  return true;
}

}  // namespace

FrameMemory estimate_frame_memory(BackendKind backend, std::size_t gaussians, int width, int height,
                                  std::uint64_t pairs, int threads) {
  const std::uint64_t w = static_cast<std::uint64_t>(std::max(width, 0));
  const std::uint64_t h = static_cast<std::uint64_t>(std::max(height, 0));
  const std::uint64_t pixels = w * h;
  const std::uint64_t tiles = ((w + gm::kTileSize - 1) / gm::kTileSize) * ((h + gm::kTileSize - 1) / gm::kTileSize);
  const std::uint64_t n = gaussians;
  FrameMemory m;
  m.image = pixels * 3 * sizeof(float);
  if (backend == BackendKind::cpu) {
    // cpu::Frame: per Gaussian its footprint, cull flag, blend data, opacity terms, depth bits
    // and the depth sort's two key arrays (sized to the Gaussians in view: the most they take);
    // per tile tile_start and each emit chunk's histogram (as many chunks as a scene of any size
    // gets); per pair the emitted (tile, id) and the id in its tile's list.
    m.per_gaussian = n * (sizeof(gm::Footprint) + sizeof(std::uint8_t) + sizeof(cpu::BlendGaussian) +
                          2 * sizeof(float) + sizeof(std::uint32_t) + 2 * sizeof(std::uint64_t));
    const std::uint64_t emit_chunks = static_cast<std::uint64_t>(cpu::emit_chunk_count(threads, ~std::uint64_t{0}));
    m.per_tile = (tiles + 1) * sizeof(std::uint64_t) + emit_chunks * tiles * sizeof(std::uint32_t);
    m.pairs = pairs * 3 * sizeof(std::uint32_t);
    m.host = m.image + m.per_gaussian + m.per_tile + m.pairs;
  } else {
    // The CUDA pipeline's buffers: footprints, pair counts and offsets, blend data per
    // Gaussian; one range per tile; double-buffered 64-bit keys and 32-bit values per pair.
    m.per_gaussian = n * (sizeof(gm::Footprint) + 2 * sizeof(std::uint32_t) + sizeof(cpu::BlendGaussian));
    m.per_tile = tiles * 2 * sizeof(std::uint32_t);
    m.pairs = pairs * 2 * (sizeof(std::uint64_t) + sizeof(std::uint32_t));
    m.host = m.image;  // the frame copied back
    m.device = m.image + m.per_gaussian + m.per_tile + m.pairs;
  }
  return m;
}

AvailableMemory available_host_memory() {
  AvailableMemory out;
  auto consider = [&out](std::uint64_t bytes, const char* name) {
    if (out.limited_by.empty() || bytes < out.bytes) {
      out.bytes = bytes;
      out.limited_by = name;
    }
  };
  std::uint64_t bytes = 0;
  if (read_mem_available(&bytes)) consider(bytes, "MemAvailable in /proc/meminfo");
  if (read_address_space_left(&bytes)) consider(bytes, "the address-space limit, RLIMIT_AS");
  if (read_cgroup_left(&bytes)) consider(bytes, "the cgroup's memory.max");
  return out;
}

std::uint64_t system_available_memory() {
  std::uint64_t bytes = 0;
  return read_mem_available(&bytes) ? bytes : 0;
}

std::string format_bytes(std::uint64_t bytes) {
  char text[32];
  if (bytes >= 1000000000ull)
    std::snprintf(text, sizeof text, "%.1f GB", bytes / 1e9);
  else if (bytes < 1000000ull)
    std::snprintf(text, sizeof text, "%llu bytes", static_cast<unsigned long long>(bytes));
  else
    std::snprintf(text, sizeof text, "%.1f MB", bytes / 1e6);
  return text;
}

std::uint64_t byte_count(double bytes) {
  if (!(bytes > 0)) return 0;
  return bytes >= 18446744073709551615.0 ? std::numeric_limits<std::uint64_t>::max() : static_cast<std::uint64_t>(bytes);
}

std::string frame_memory_shortfall(const FrameMemory& need, int width, int height, const AvailableMemory& available) {
  if (available.limited_by.empty() || need.host <= available.bytes) return "";
  std::ostringstream text;
  text << "a " << width << "x" << height << " frame needs about " << format_bytes(need.host) << " of memory (image "
       << format_bytes(need.image);
  if (need.device == 0)
    text << ", per tile " << format_bytes(need.per_tile) << ", per Gaussian " << format_bytes(need.per_gaussian)
         << ", pairs " << format_bytes(need.pairs);
  text << ") but " << format_bytes(available.bytes) << " is available (" << available.limited_by << ")";
  return text.str();
}

}  // namespace flashgs
