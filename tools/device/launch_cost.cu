// What a frame's first launches cost the host and the GPU, on the GPU machine (it found the
// first kernel launch of each frame taking 12-25 us of host time, later ones 5-10 us). Each mode
// runs 50 "frames" from an idle GPU, as `flashgs bench` does, and prints the median host time
// of each call; run it under gpu_trace.cpp (gpu_check.sh step launch-cost) for the GPU side.
//   direct:  memset, event, launch (560 B of parameters), launch, event
//   nomemset: event, launch, launch, event
//   small:   memset, event, launch (16 B), launch, event
//   graph:   the direct sequence as a CUDA graph, its kernel parameters set each frame, one launch
//   capture: the direct sequence captured each frame (events as external nodes), the graph
//            instantiated once and updated from each capture, one launch
// Built by tools/device/prebuild.sh (nvcc, sm_90) into .deps/launch_cost.
#include <cuda_runtime.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace {

struct BigParams {
  float values[140];  // 560 bytes: the preprocess kernel's DeviceScene + FrameBuffers + PreprocessArgs
};

__global__ void big_kernel(BigParams p, unsigned* out) {
  if (threadIdx.x == 0 && blockIdx.x == 0) atomicAdd(out, static_cast<unsigned>(p.values[threadIdx.x % 140]));
}

__global__ void small_kernel(unsigned* out, unsigned add) {
  if (threadIdx.x == 0 && blockIdx.x == 0) atomicAdd(out, add);
}

void check(cudaError_t status, const char* what) {
  if (status != cudaSuccess) {
    std::fprintf(stderr, "%s: %s\n", what, cudaGetErrorString(status));
    std::exit(1);
  }
}

using Clock = std::chrono::steady_clock;
double us_since(Clock::time_point t) { return std::chrono::duration<double, std::micro>(Clock::now() - t).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "direct";
  cudaStream_t stream;
  check(cudaStreamCreateWithFlags(&stream, cudaStreamNonBlocking), "stream");
  unsigned* counters = nullptr;
  check(cudaMalloc(&counters, 256), "malloc");
  cudaEvent_t begin, end;
  check(cudaEventCreate(&begin), "event");
  check(cudaEventCreate(&end), "event");
  BigParams params{};
  const int blocks = 2000;  // a preprocess-sized grid of short blocks

  cudaGraphExec_t exec = nullptr;
  cudaGraphNode_t first_kernel = nullptr;
  cudaKernelNodeParams node{};
  void* node_args[2] = {&params, &counters};
  if (mode == "graph") {
    cudaGraph_t graph;
    check(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal), "capture");
    check(cudaMemsetAsync(counters, 0, 216, stream), "memset");
    check(cudaEventRecord(begin, stream), "record");
    big_kernel<<<blocks, 256, 0, stream>>>(params, counters);
    big_kernel<<<blocks, 256, 0, stream>>>(params, counters);
    check(cudaEventRecord(end, stream), "record");
    check(cudaStreamEndCapture(stream, &graph), "end capture");
    size_t count = 0;
    check(cudaGraphGetNodes(graph, nullptr, &count), "nodes");
    std::vector<cudaGraphNode_t> nodes(count);
    check(cudaGraphGetNodes(graph, nodes.data(), &count), "nodes");
    for (cudaGraphNode_t n : nodes) {
      cudaGraphNodeType type;
      check(cudaGraphNodeGetType(n, &type), "node type");
      if (type == cudaGraphNodeTypeKernel && !first_kernel) first_kernel = n;
    }
    check(cudaGraphKernelNodeGetParams(first_kernel, &node), "node params");
    check(cudaGraphInstantiate(&exec, graph, 0), "instantiate");
    check(cudaGraphDestroy(graph), "graph destroy");
  }

  std::vector<double> t_memset, t_record, t_first, t_second, t_total;
  for (int frame = 0; frame < 60; ++frame) {
    check(cudaStreamSynchronize(stream), "sync");
    params.values[frame % 140] = static_cast<float>(frame);
    const Clock::time_point start = Clock::now();
    Clock::time_point t = start;
    if (mode == "capture") {
      cudaGraph_t graph;
      check(cudaStreamBeginCapture(stream, cudaStreamCaptureModeThreadLocal), "capture");
      check(cudaMemsetAsync(counters, 0, 216, stream), "memset");
      check(cudaEventRecordWithFlags(begin, stream, cudaEventRecordExternal), "record");
      big_kernel<<<blocks, 256, 0, stream>>>(params, counters);
      big_kernel<<<blocks, 256, 0, stream>>>(params, counters);
      check(cudaEventRecordWithFlags(end, stream, cudaEventRecordExternal), "record");
      check(cudaStreamEndCapture(stream, &graph), "end capture");
      t_first.push_back(us_since(t));
      t = Clock::now();
      cudaGraphExecUpdateResultInfo info{};
      if (!exec || cudaGraphExecUpdate(exec, graph, &info) != cudaSuccess) {
        cudaGetLastError();
        if (exec) check(cudaGraphExecDestroy(exec), "exec destroy");
        check(cudaGraphInstantiate(&exec, graph, 0), "instantiate");
      }
      check(cudaGraphDestroy(graph), "graph destroy");
      t_memset.push_back(us_since(t));  // (the update)
      t = Clock::now();
      check(cudaGraphLaunch(exec, stream), "graph launch");
      t_second.push_back(us_since(t));
    } else if (mode == "graph") {
      node.kernelParams = node_args;
      check(cudaGraphExecKernelNodeSetParams(exec, first_kernel, &node), "set params");
      t_first.push_back(us_since(t));
      t = Clock::now();
      check(cudaGraphLaunch(exec, stream), "graph launch");
      t_second.push_back(us_since(t));
    } else {
      if (mode != "nomemset") {
        check(cudaMemsetAsync(counters, 0, 216, stream), "memset");
        t_memset.push_back(us_since(t));
        t = Clock::now();
      }
      check(cudaEventRecord(begin, stream), "record");
      t_record.push_back(us_since(t));
      t = Clock::now();
      if (mode == "small") small_kernel<<<blocks, 256, 0, stream>>>(counters, 1u);
      else big_kernel<<<blocks, 256, 0, stream>>>(params, counters);
      t_first.push_back(us_since(t));
      t = Clock::now();
      if (mode == "small") small_kernel<<<blocks, 256, 0, stream>>>(counters, 2u);
      else big_kernel<<<blocks, 256, 0, stream>>>(params, counters);
      t_second.push_back(us_since(t));
      check(cudaEventRecord(end, stream), "record");
    }
    t_total.push_back(us_since(start));
  }
  check(cudaStreamSynchronize(stream), "sync");
  float gpu_ms = 0;
  check(cudaEventElapsedTime(&gpu_ms, begin, end), "elapsed");
  auto show = [](const char* what, const std::vector<double>& v) {
    if (!v.empty()) std::printf(" %s %.1f", what, median(std::vector<double>(v.begin() + 10, v.end())));
  };
  std::printf("%s: host us (median of 50 frames):", mode.c_str());
  show(mode == "capture" ? "update" : "memset", t_memset);
  show("record", t_record);
  show(mode == "graph" ? "set-params" : mode == "capture" ? "capture" : "first-launch", t_first);
  show(mode == "graph" || mode == "capture" ? "graph-launch" : "second-launch", t_second);
  show("all", t_total);
  std::printf("; last frame's begin->end on the GPU %.1f us\n", gpu_ms * 1000.0f);
  return 0;
}
