// A GPU timeline for machines without Nsight Systems: a CUDA injection library
// (CUDA_INJECTION64_PATH=libgputrace.so) that records every kernel, memset and memcpy, and with
// FLASHGS_TRACE_API set every runtime call, with CUPTI's activity API, and writes
// "kind start_ns end_ns name" lines to $FLASHGS_TRACE_OUT at exit. Built on the development
// machine by tools/device/prebuild.sh into .deps; run by gpu_check.sh's `trace` step.
#include <cupti.h>

#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

namespace {

constexpr std::size_t kBufferBytes = 8u << 20;
std::mutex g_lines_mutex;
std::vector<std::string> g_lines;

void CUPTIAPI buffer_requested(uint8_t** buffer, size_t* size, size_t* max_records) {
  *buffer = static_cast<uint8_t*>(std::aligned_alloc(8, kBufferBytes));
  *size = kBufferBytes;
  *max_records = 0;
}

void CUPTIAPI buffer_completed(CUcontext, uint32_t, uint8_t* buffer, size_t, size_t valid) {
  CUpti_Activity* record = nullptr;
  std::lock_guard<std::mutex> lock(g_lines_mutex);
  while (cuptiActivityGetNextRecord(buffer, valid, &record) == CUPTI_SUCCESS) {
    char line[512];
    if (record->kind == CUPTI_ACTIVITY_KIND_CONCURRENT_KERNEL || record->kind == CUPTI_ACTIVITY_KIND_KERNEL) {
      const auto* k = reinterpret_cast<const CUpti_ActivityKernel10*>(record);
      std::snprintf(line, sizeof line, "kernel %llu %llu %s", static_cast<unsigned long long>(k->start),
                    static_cast<unsigned long long>(k->end), k->name ? k->name : "?");
    } else if (record->kind == CUPTI_ACTIVITY_KIND_MEMSET) {
      const auto* m = reinterpret_cast<const CUpti_ActivityMemset4*>(record);
      std::snprintf(line, sizeof line, "memset %llu %llu %llu", static_cast<unsigned long long>(m->start),
                    static_cast<unsigned long long>(m->end), static_cast<unsigned long long>(m->bytes));
    } else if (record->kind == CUPTI_ACTIVITY_KIND_MEMCPY) {
      const auto* m = reinterpret_cast<const CUpti_ActivityMemcpy6*>(record);
      std::snprintf(line, sizeof line, "memcpy %llu %llu %llu", static_cast<unsigned long long>(m->start),
                    static_cast<unsigned long long>(m->end), static_cast<unsigned long long>(m->bytes));
    } else if (record->kind == CUPTI_ACTIVITY_KIND_RUNTIME) {
      const auto* a = reinterpret_cast<const CUpti_ActivityAPI*>(record);
      const char* name = nullptr;
      cuptiGetCallbackName(CUPTI_CB_DOMAIN_RUNTIME_API, a->cbid, &name);
      std::snprintf(line, sizeof line, "api %llu %llu %s", static_cast<unsigned long long>(a->start),
                    static_cast<unsigned long long>(a->end), name ? name : "?");
    } else {
      continue;
    }
    g_lines.emplace_back(line);
  }
  std::free(buffer);
}

void write_trace() {
  cuptiActivityFlushAll(1);
  const char* path = std::getenv("FLASHGS_TRACE_OUT");
  std::FILE* out = std::fopen(path ? path : "gpu_trace.txt", "w");
  if (!out) return;
  std::lock_guard<std::mutex> lock(g_lines_mutex);
  for (const std::string& l : g_lines) std::fprintf(out, "%s\n", l.c_str());
  std::fclose(out);
}

}  // namespace

extern "C" int InitializeInjection() {
  if (cuptiActivityRegisterCallbacks(buffer_requested, buffer_completed) != CUPTI_SUCCESS) return 0;
  cuptiActivityEnable(CUPTI_ACTIVITY_KIND_CONCURRENT_KERNEL);
  cuptiActivityEnable(CUPTI_ACTIVITY_KIND_MEMSET);
  cuptiActivityEnable(CUPTI_ACTIVITY_KIND_MEMCPY);
  if (std::getenv("FLASHGS_TRACE_API")) cuptiActivityEnable(CUPTI_ACTIVITY_KIND_RUNTIME);
  std::atexit(write_trace);
  return 1;
}
