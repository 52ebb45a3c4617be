// BackendTuning: the knobs of how a backend makes a frame (its speed, never its image), and
// kTuningKnobs, the one table of their names, ranges and what each trades.
#pragma once

#include <string>
#include <string_view>

namespace flashgs {

// A knob of kind `mode` holds kTuningAuto (the backend decides by scene and frame), 0 or 1.
constexpr long long kTuningAuto = -1;

// Every knob's default is its initialiser here; renderers are made with these values, a
// benchmark or test changes them (tuning_from_environment, apply_tuning_setting).
struct BackendTuning {
  long long bin_sort = kTuningAuto;
  long long bin_sort_shared_pairs = 1024;  // the bin sort's shared-memory limit (its range's max)
  long long bin_overlap = kTuningAuto;
  long long emit_bin_counts = kTuningAuto;
  long long sort_key_bits = 32;
  long long chunk_cull = kTuningAuto;
  long long spatial_order = kTuningAuto;
  long long dense_tiles_first = kTuningAuto;
  long long large_box_tiles = 32;
  long long deferred_item_chunks = 4;
  long long blend_region_width = 8;
  long long blend_stop_bound = 1;
  long long initial_records = 1ll << 21;  // 100 MB of blend records
  long long upload_times = 0;
  std::string cpu_simd;  // a Highway target name; empty: the CPU's best
};

enum class TuningKind {
  mode,    // auto, 0 or 1
  flag,    // 0 or 1
  number,  // an integer in [min, max]
  choice,  // min or max
  text,    // a name (cpu_simd)
};

using TuningNumber = long long BackendTuning::*;
using TuningText = std::string BackendTuning::*;

// One knob. Adding one: a member above, a row below, and the backend code that reads it; the
// environment variable, `flashgs bench --set/--tuning/--list-tuning`, the report and
// docs/TUNING.md follow (tests/test_backend_tuning.cpp checks the docs against this table).
struct TuningKnob {
  const char* name;      // "bin_sort": flashgs bench --set bin_sort=0; FLASHGS_BIN_SORT
  TuningKind kind;
  TuningNumber number;   // the member (null for kind text)
  TuningText text;       // the member of kind text (else null)
  long long min, max;    // kind number: the range; choice: the two values
  const char* backend;   // "cuda" or "cpu": the backend that reads it
  const char* default_text;  // the default in words (docs and --list-tuning)
  const char* trades;    // what the other values do
  const char* measured;  // where its effect was measured
};

inline constexpr TuningKnob kTuningKnobs[] = {
    {"bin_sort", TuningKind::mode, &BackendTuning::bin_sort, nullptr, 0, 1, "cuda",
     "auto: per-bin sort where it pays (`bin_sort_pays`: few pairs per bin)",
     "1 = sort every binned frame per bin, 0 = CUB's radix sort over the whole frame",
     "docs/PERFORMANCE.md, \"a sort shaped for the bins\", 2026-12-03"},
    {"bin_sort_shared_pairs", TuningKind::number, &BackendTuning::bin_sort_shared_pairs, nullptr, 0, 1024, "cuda",
     "1024 (the most shared memory holds)", "the largest bin sorted in shared memory; larger bins sort in global memory",
     "docs/PERFORMANCE.md, bin sort, 2026-12-03"},
    {"bin_overlap", TuningKind::mode, &BackendTuning::bin_overlap, nullptr, 0, 1, "cuda",
     "auto: on where the GPU can launch a kernel early (sm_90 and later; 1 = the same)",
     "0 = the blend waits for the bin blocks instead of running beside them",
     "docs/PERFORMANCE.md, \"the blend runs beside the bin blocks\", 2026-12-04"},
    {"emit_bin_counts", TuningKind::mode, &BackendTuning::emit_bin_counts, nullptr, 0, 1, "cuda",
     "auto (`emit_bin_counts_pays`: 1080p-class frames)",
     "1 = emission counts pairs per bin as it writes them, 0 = a counting pass does",
     "docs/PERFORMANCE.md, \"the pairs counted per bin by emission\", 2026-12-05"},
    {"sort_key_bits", TuningKind::number, &BackendTuning::sort_key_bits, nullptr, 16, 32, "cuda", "32",
     "the compact key's length: fewer bits = fewer radix passes but coarser depth bins",
     "docs/PERFORMANCE.md, sort key bits, 2026-12-03"},
    {"chunk_cull", TuningKind::mode, &BackendTuning::chunk_cull, nullptr, 0, 1, "cuda",
     "auto: scenes of 1M Gaussians and more (`kChunkCullMinGaussians`)",
     "1 = cull chunks of 256 Gaussians by their bounds in any scene, 0 = project every Gaussian",
     "docs/PERFORMANCE.md, chunk cull (3.5M tiled scene: project 9% shorter; 100M: 2.8x), 2026-12-04"},
    {"spatial_order", TuningKind::mode, &BackendTuning::spatial_order, nullptr, 0, 1, "cuda",
     "auto: scenes of 256k Gaussians and more whose stored order is not spatially coherent",
     "1 = upload every scene in spatial order, 0 = never",
     "docs/PERFORMANCE.md, \"A scene's stored order\", 2026-12-04"},
    {"dense_tiles_first", TuningKind::mode, &BackendTuning::dense_tiles_first, nullptr, 0, 1, "cuda",
     "auto (`dense_order_pays`: the last frame's fullest tile outlasted a wave of the blend)",
     "1 = order tiles heaviest first every frame, 0 = never", "docs/PERFORMANCE.md, dense tiles first, 2026-12-03"},
    {"large_box_tiles", TuningKind::number, &BackendTuning::large_box_tiles, nullptr, 1, 1 << 20, "cuda",
     "32",
     "the box size (tiles, or bins with macro bins) above which warps emit a Gaussian's pairs after preprocess",
     "docs/PERFORMANCE.md, warp emission threshold swept 8/16/32/64"},
    {"deferred_item_chunks", TuningKind::number, &BackendTuning::deferred_item_chunks, nullptr, 1, 32, "cuda",
     "4", "32-bin chunks per work item of deferred emission",
     "docs/PERFORMANCE.md, deferred emission work items, 2026-12-03"},
    {"blend_region_width", TuningKind::choice, &BackendTuning::blend_region_width, nullptr, 8, 16, "cuda",
     "8 (8 x 8 pixel regions)", "16 = 16 x 4 regions per warp in the blend",
     "docs/PERFORMANCE.md, \"balance, fewer sort passes, cheaper blend\", 2026-11-24"},
    {"blend_stop_bound", TuningKind::flag, &BackendTuning::blend_stop_bound, nullptr, 0, 1, "cuda", "1",
     "0 = the blend tests its stop rule on every staged Gaussian (same image, slower; the tests compare both)",
     "docs/PERFORMANCE.md, blend stop bound, 2026-12-03"},
    {"initial_records", TuningKind::number, &BackendTuning::initial_records, nullptr, 1, 1ll << 40, "cuda",
     "2,097,152 (100 MB of blend records)",
     "the records a scene's first frame starts with; a larger view grows them once (tests set 1 to exercise growth)",
     "tests: `CudaRecords.GrowingFromOneRecordChangesNoByte`"},
    {"upload_times", TuningKind::flag, &BackendTuning::upload_times, nullptr, 0, 1, "cuda", "0",
     "1 = print where each upload's time went (order, allocation, packing, waiting)",
     "docs/PERFORMANCE.md, scene upload, 2026-12-04"},
    {"cpu_simd", TuningKind::text, nullptr, &BackendTuning::cpu_simd, 0, 0, "cpu",
     "the widest SIMD target the CPU has",
     "caps the CPU kernels' target (AVX3, AVX2, SSE4, ...; `scalar`): the same image, slower (the tests force each)",
     "docs/PERFORMANCE.md, CPU blend SIMD (AVX2 cap: 98-100 ms), 2026-12-04"},
};

// The knob of this name, for a compile-time check of its range (cuda_renderer.cu).
constexpr const TuningKnob& tuning_knob(std::string_view name) {
  for (const TuningKnob& knob : kTuningKnobs)
    if (name == knob.name) return knob;
  throw "no tuning knob of this name";
}

// The knob's environment variable: FLASHGS_ and its name in capitals (FLASHGS_BIN_SORT).
std::string tuning_variable(const TuningKnob& knob);

// The knob of this name, or null.
const TuningKnob* find_tuning_knob(const std::string& name);

// The defaults, each knob overridden by its environment variable where set: the one place the
// environment is read, so that `FLASHGS_SORT_KEY_BITS=24 flashgs bench` and the tests keep
// working. A variable's text is read as the backend always read it: a number out of range is
// clamped into it, a mode or flag is 1 unless it reads as 0, a choice not of its two values is
// the default.
BackendTuning tuning_from_environment();

// Sets `knob` from typed text (`--set bin_sort=0`): auto (modes only), an integer in range,
// or a target name (cpu_simd). Throws flashgs::Error, naming `what` and the knob, otherwise.
void apply_tuning_value(BackendTuning& tuning, const TuningKnob& knob, const std::string& value, const std::string& what);
// "NAME=VALUE" (`what` names the option for the message).
void apply_tuning_setting(BackendTuning& tuning, const std::string& setting, const std::string& what);

// A knob's value as text: "auto", a number, or a target name ("" for cpu_simd's default).
std::string tuning_value_text(const BackendTuning& tuning, const TuningKnob& knob);
// Every knob as "name=value", space separated, in table order (what a run used).
std::string tuning_summary(const BackendTuning& tuning);
// The knobs whose values differ from the defaults, as "name=value" (empty: all defaults).
std::string tuning_changes(const BackendTuning& tuning);

// The knobs for `--list-tuning`: a line each with its variable, values and default.
std::string tuning_listing();
// docs/TUNING.md's table of the knobs, generated from kTuningKnobs.
std::string tuning_table_markdown();

}  // namespace flashgs
