// `flashgs bench`: per-stage timings, pairs, memory and image error of every configuration
// over a camera set and resolutions; prints a table and writes JSON.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "backend_factory.h"
#include "commands.h"
#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "flashgs/frame_memory.h"
#include "flashgs/generators.h"
#include "flashgs/io.h"
#include "flashgs/parse.h"
#include "flashgs/percentile.h"
#include "option_checks.h"
#include "scene_source.h"
#include "tuning_options.h"

namespace flashgs::cli {
namespace {

struct BenchArgs {
  SceneArgs scene;
  std::string backend = "auto";
  std::vector<std::string> resolutions = {"1920x1080", "3840x2160"};
  std::vector<std::string> configs = {"all"};
  std::string cameras_text;      // --camera-list as typed
  CLI::Option* cameras_option = nullptr;
  // not given: 0, 2, ..., 34 (the 18 views of ANCHORS.md)
  int threads = 0;                 // CPU backend: 0 = every core
  std::string cpu_blend = "simd";  // CPU backend: simd or scalar (the reference kernel)
  int warmup = 3;
  int repeat = 10;
  // queued: frames queued back to back as the viewer renders them (GPU backends), the host's
  // launches for one overlapping the GPU's work on the last; waited: each frame downloaded and
  // waited for, as `flashgs render` does.
  std::string frames = "queued";
  int copies = 1;  // --tile: the scene copied on a grid in memory (scale benchmarks)
  std::string json_path = "bench.json";
  KernelOption kernel;  // applied to every configuration
  TuningOptions tuning;  // every configuration runs once per tuning variant
};

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// The configurations by name (their labels): baseline, flash, flash with one switch off, both
// algorithms with gsplat's anti-aliased kernel (baseline-antialiased, flash-antialiased: its cost
// against the classic rows of the same run), and flash with the precision options: those that
// change the scene's bytes (fp16_sh, fp16_shape, both), then the half blend alone and with them
// (fp16_blend; CUDA only).
std::vector<std::pair<std::string, RenderOptions>> known_configs() {
  std::vector<std::pair<std::string, RenderOptions>> out;
  for (const RenderOptions& o : single_switch_configs()) out.emplace_back(o.label(), o);
  for (RenderOptions o : {RenderOptions::baseline(), RenderOptions{}}) {
    o.kernel = SplatKernel::antialiased();
    out.emplace_back(o.label(), o);
  }
  for (const RenderOptions& o : fp16_configs()) out.emplace_back(o.label(), o);
  for (const RenderOptions& o : fp16_blend_configs()) out.emplace_back(o.label(), o);
  return out;
}

std::string known_config_names() {
  std::string names;
  for (const auto& c : known_configs()) names += " " + c.first;
  return names;
}

std::vector<std::pair<std::string, RenderOptions>> select_configs(const std::vector<std::string>& wanted,
                                                                  bool cpu) {
  const auto known = known_configs();
  std::vector<std::pair<std::string, RenderOptions>> out;
  for (const std::string& w : wanted) {
    if (w == "all") {
      for (const auto& c : known) {
        // An option the CPU does not honour: its row would repeat an earlier one ("flash" for a
        // GPU switch, flash-fp16_sh-fp16_shape for the fp16 storage with the half blend).
        const bool repeats = std::any_of(known.begin(), known.end(), [&](const auto& earlier) {
          return &earlier < &c && earlier.second.seen_by(Backend::cpu) == c.second.seen_by(Backend::cpu);
        });
        if (!(cpu && repeats)) out.push_back(c);
      }
      continue;
    }
    auto it = std::find_if(known.begin(), known.end(), [&](const auto& c) { return c.first == w; });
    if (it == known.end()) throw Error("bench: unknown config \"" + w + "\" (all" + known_config_names() + ")");
    out.push_back(*it);
  }
  // The baseline is rendered anyway (it is the reference image); list it first, once.
  out.erase(std::remove_if(out.begin(), out.end(), [](const auto& c) { return c.first == "baseline"; }), out.end());
  out.insert(out.begin(), known.front());
  return out;
}

const char* kStages[] = {"project", "emit", "sort", "ranges", "blend", "total"};

double stage_ms(const StageTimes& t, int s) {
  switch (s) {
    case 0: return t.project_ms;
    case 1: return t.emit_ms;
    case 2: return t.sort_ms;
    case 3: return t.ranges_ms;
    case 4: return t.blend_ms;
    default: return t.total_ms;
  }
}

// What one config collected at one resolution: per camera, the median of its repeats.
struct ConfigRun {
  std::string name;
  RenderOptions options;
  BackendTuning tuning;
  std::unique_ptr<Renderer> renderer;
  std::vector<double> stage[6];  // per camera
  std::vector<double> kv, sorted, visible, psnr, max_abs;
  std::uint64_t memory_max = 0, peak_max = 0;
  std::uint64_t scene_device_bytes = 0;  // the scene as the backend holds it (0 on the CPU)
  double upload_ms = 0, first_frame_ms = -1;  // wall clock: set_scene, and the first render
  std::vector<double> wall_ms;  // per camera, queued frames: wall clock per timed frame
  std::string blend_note;  // blend_time_note of a timed frame whose blend time held more than the blend
  nlohmann::json per_camera = nlohmann::json::array();
};

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

// The scene, tiled --tile times when asked (refused with the figures when the copies cannot fit).
std::shared_ptr<const Scene> load_bench_scene(const BenchArgs& args, const std::string& scene_path) {
  std::shared_ptr<const Scene> scene = load_scene_verbose(scene_path, args.scene.lod, args.scene.read_options());
  if (args.copies <= 1) return scene;
  const std::uint64_t wanted = static_cast<std::uint64_t>(scene->byte_size()) * args.copies;
  const AvailableMemory available = available_host_memory();
  if (available.bytes > 0 && wanted > available.bytes)
    throw Error("--tile: " + std::to_string(args.copies) + " copies need " + format_bytes(wanted) +
                " of host memory, " + format_bytes(available.bytes) + " is available (" + available.limited_by + ")");
  return std::make_shared<const Scene>(tile_scene(*scene, args.copies));
}

// --camera-list, or cameras 0, 2, ..., 34; each checked against the file.
std::vector<int> bench_camera_ids(const BenchArgs& args, std::size_t camera_count, const std::string& cameras_path) {
  const bool listed = args.cameras_option->count() > 0;
  std::vector<int> ids = listed ? parse_index_list("--camera-list", args.cameras_text) : std::vector<int>{};
  if (!listed)
    for (int i = 0; i <= 34; i += 2) ids.push_back(i);
  check_camera_indices(listed ? "--camera-list" : "the default --camera-list", ids, camera_count, cameras_path);
  return ids;
}

// What a bench run is: the backend chosen and whether its frames are queued.
struct BenchBackend {
  std::string name;
  bool cpu = true, queued = false;
  CpuBlend cpu_blend = CpuBlend::simd;
};

// The backend, probed once: every resolution's first frame must fit in memory.
BenchBackend probe_backend(const BenchArgs& args, const std::vector<Resolution>& resolutions, const Camera& first_camera,
                           std::size_t gaussians, const BackendTuning& tuning) {
  BenchBackend b;
  b.cpu_blend = args.cpu_blend == "scalar" ? CpuBlend::scalar : CpuBlend::simd;
  auto probe = create_backend(args.backend, args.threads, b.cpu_blend, tuning);
  for (const Resolution& size : resolutions)
    check_frame_fits(*probe, first_camera.resized(size.width, size.height), gaussians, "--resolutions");
  b.cpu = probe->name().rfind("cpu", 0) == 0;
  b.name = probe->name();
  b.queued = args.frames == "queued" && can_queue_frames(*probe);
  return b;
}

// One row of the run: a configuration and the tuning it runs with.
struct RunConfig {
  std::string name;
  RenderOptions options;
  BackendTuning tuning;
};

// The configurations in run order, each once per tuning variant: the baselines first (each row
// is judged against the baseline of its kernel), every one without a kernel of its own drawn
// with the scene's (or --kernel's).
std::vector<RunConfig> run_configs(const BenchArgs& args, bool cpu, const SplatKernel& kernel,
                                   const std::vector<TuningVariant>& variants) {
  std::vector<RunConfig> configs;
  for (auto [name, options] : select_configs(args.configs, cpu)) {
    if (options.kernel == SplatKernel::classic()) options.kernel = kernel;
    for (const TuningVariant& variant : variants) configs.push_back({with_tuning_label(name, variant), options, variant.tuning});
  }
  std::stable_partition(configs.begin(), configs.end(), [](const RunConfig& c) { return c.options.is_baseline(); });
  return configs;
}

nlohmann::json tuning_json(const BackendTuning& tuning) {
  nlohmann::json j = nlohmann::json::object();
  for (const TuningKnob& knob : kTuningKnobs) j[knob.name] = tuning_value_text(tuning, knob);
  return j;
}

// One camera's frames of one config: the first frame (timed apart), warm-up and timed frames,
// then the image, its counts and its difference from the baseline of its kernel.
void measure_camera(ConfigRun& r, const Camera& camera, int id, const BenchArgs& args, bool queued,
                    std::map<std::string, Image>& baseline_of_kernel, const RenderOptions& first_options) {
  Image image;
  FrameStats stats;
  if (r.first_frame_ms < 0) {  // the first frame allocates its buffers: timed apart, wall clock
    const auto first_start = std::chrono::steady_clock::now();
    r.renderer->render(camera, r.options, image, &stats);
    r.first_frame_ms = ms_since(first_start);
  }
  const int repeat = std::max(1, args.repeat);
  std::vector<double> samples[6];
  if (queued) {
    // A queued frame reports the previous frame's stage times: one frame more than timed,
    // then a waited frame, which finishes the queue and gives the image and its counts.
    for (int w = 0; w <= args.warmup; ++w) render_queued(*r.renderer, camera, r.options, &stats);
    const auto timed_start = std::chrono::steady_clock::now();
    for (int k = 0; k < repeat; ++k) {
      render_queued(*r.renderer, camera, r.options, &stats);
      for (int s = 0; s < 6; ++s) samples[s].push_back(stage_ms(stats.times, s));
    }
    r.wall_ms.push_back(ms_since(timed_start) / repeat);
    r.renderer->render(camera, r.options, image, &stats);
  } else {
    for (int w = 0; w < args.warmup; ++w) r.renderer->render(camera, r.options, image, &stats);
    for (int k = 0; k < repeat; ++k) {
      r.renderer->render(camera, r.options, image, &stats);
      for (int s = 0; s < 6; ++s) samples[s].push_back(stage_ms(stats.times, s));
    }
  }
  nlohmann::json cam;
  cam["camera"] = id;
  for (int s = 0; s < 6; ++s) {
    const double m = median(samples[s]);
    r.stage[s].push_back(m);
    cam[std::string(kStages[s]) + "_ms"] = m;
  }
  if (*blend_time_note(stats.times)) r.blend_note = blend_time_note(stats.times);
  r.kv.push_back(static_cast<double>(stats.kv_pairs));
  r.sorted.push_back(static_cast<double>(stats.sorted_pairs));
  r.visible.push_back(static_cast<double>(stats.visible));
  r.memory_max = std::max<std::uint64_t>(r.memory_max, stats.device_memory_bytes);
  r.peak_max = std::max<std::uint64_t>(r.peak_max, stats.device_peak_bytes);
  r.scene_device_bytes = stats.scene_device_bytes;
  cam["kv_pairs"] = stats.kv_pairs;
  cam["sorted_pairs"] = stats.sorted_pairs;
  cam["visible"] = stats.visible;
  cam["culled"] = {{"near", stats.culled_near},
                   {"offscreen", stats.culled_offscreen},
                   {"low_opacity", stats.culled_low_opacity},
                   {"degenerate", stats.culled_degenerate},
                   {"by_chunk", stats.culled_by_chunk}};
  if (r.options.is_baseline()) baseline_of_kernel[r.options.kernel.spec()] = image;
  const auto own = baseline_of_kernel.find(r.options.kernel.spec());
  // Without a baseline of its kernel in the run: the first row's, the scene's kernel.
  const Image& reference =
      own != baseline_of_kernel.end() ? own->second : baseline_of_kernel.at(first_options.kernel.spec());
  const ImageDifference d = compare_images(reference, image);
  r.psnr.push_back(d.psnr_db);
  r.max_abs.push_back(d.max_abs);
  cam["psnr_db_vs_baseline"] = finite_or_null(d.psnr_db);
  cam["max_abs_vs_baseline"] = d.max_abs;
  cam["non_finite"] = d.non_finite;
  r.per_camera.push_back(cam);
}

// One config's row at one resolution: its JSON result, its table line and its upload lines.
void summarise(const ConfigRun& r, const std::string& resolution, nlohmann::json& results, std::string& table,
               std::string& uploads) {
  nlohmann::json j;
  j["resolution"] = resolution;
  j["config"] = r.name;
  j["label"] = r.options.label();
  j["tuning"] = tuning_json(r.tuning);
  for (int s = 0; s < 6; ++s)
    j["ms"][kStages[s]] = {{"median", median(r.stage[s])}, {"p95", percentile(r.stage[s], kTailPercentile)}};
  j["kv_pairs"] = {{"median", median(r.kv)}, {"max", *std::max_element(r.kv.begin(), r.kv.end())}};
  j["sorted_pairs_median"] = median(r.sorted);
  j["visible_median"] = median(r.visible);
  j["memory_bytes"] = {{"working_max", r.memory_max}, {"peak", r.peak_max}, {"scene_device", r.scene_device_bytes}};
  j["sort_in_blend"] = !r.blend_note.empty();
  j["upload_ms"] = r.upload_ms;
  if (!r.wall_ms.empty()) j["wall_ms_per_frame_median"] = median(r.wall_ms);
  j["first_frame_ms"] = r.first_frame_ms;
  char upload_line[320];
  const std::string scene_bytes =
      r.scene_device_bytes ? ", scene on the device " + format_bytes(r.scene_device_bytes) : std::string();
  std::snprintf(upload_line, sizeof upload_line, "%-10s %-28s scene upload %.1f ms, first frame %.1f ms (wall clock)%s\n",
                resolution.c_str(), r.name.c_str(), r.upload_ms, r.first_frame_ms, scene_bytes.c_str());
  uploads += upload_line;
  if (!r.wall_ms.empty()) {
    std::snprintf(upload_line, sizeof upload_line,
                  "%-10s %-28s queued frames: %.3f ms apart (wall clock, median over cameras)\n", resolution.c_str(),
                  r.name.c_str(), median(r.wall_ms));
    uploads += upload_line;
  }
  if (!r.blend_note.empty()) {
    std::snprintf(upload_line, sizeof upload_line, "%-10s %-28s %s\n", resolution.c_str(), r.name.c_str(),
                  r.blend_note.c_str());
    uploads += upload_line;
  }
  const double psnr_min = *std::min_element(r.psnr.begin(), r.psnr.end());
  j["psnr_db_vs_baseline"] = {{"min", finite_or_null(psnr_min)}, {"median", finite_or_null(median(r.psnr))}};
  j["max_abs_vs_baseline"] = *std::max_element(r.max_abs.begin(), r.max_abs.end());
  j["per_camera"] = r.per_camera;
  results.push_back(j);

  char line[512];
  std::snprintf(line, sizeof line, "%-10s %-28s %7.3f %7.3f %7.3f %7.3f %7.3f %8.3f (%7.3f) %9.0f %8.1f %7s %9.2e\n",
                resolution.c_str(), r.name.c_str(), median(r.stage[0]), median(r.stage[1]), median(r.stage[2]),
                median(r.stage[3]), median(r.stage[4]), median(r.stage[5]), percentile(r.stage[5], kTailPercentile),
                median(r.kv), r.peak_max / 1e6, std::isfinite(psnr_min) ? std::to_string(psnr_min).substr(0, 6).c_str() : "inf",
                *std::max_element(r.max_abs.begin(), r.max_abs.end()));
  table += line;
}

void run(const BenchArgs& args) {
  // Everything that can be wrong with the arguments is found before the first frame.
  check_output_file("--json", args.json_path);
  const std::vector<TuningVariant> variants = args.tuning.variants();
  const BackendTuning base_tuning = args.tuning.base();
  std::vector<Resolution> resolutions;
  for (const std::string& text : args.resolutions) resolutions.push_back(parse_resolution(text));
  const std::string scene_path = args.scene.resolved_scene();
  const std::shared_ptr<const Scene> scene = load_bench_scene(args, scene_path);
  const std::string cameras_path = args.scene.resolved_cameras();
  const std::vector<Camera> all_cameras = load_cameras(cameras_path);
  const std::vector<int> camera_ids = bench_camera_ids(args, all_cameras.size(), cameras_path);
  const BenchBackend backend =
      probe_backend(args, resolutions, all_cameras[camera_ids.front()], scene->size(), base_tuning);
  const SplatKernel kernel = args.kernel.resolve(*scene);
  const std::vector<RunConfig> configs = run_configs(args, backend.cpu, kernel, variants);

  nlohmann::json out;
  out["scene"] = scene_path;
  out["copies"] = args.copies;
  out["gaussians"] = scene->size();
  out["sh_degree"] = scene->sh_degree;
  out["kernel"] = kernel.spec();
  out["kernel_from"] = args.kernel.chosen() ? "--kernel" : scene->trained_kernel.source;
  out["scene_bytes_host_layout"] = scene->byte_size();
  out["backend"] = backend.name;
  out["timing"] = backend.cpu ? "wall clock per stage (CPU)" : "GPU time per stage from CUDA events; total = sum of stages";
  out["cameras"] = camera_ids;
  out["frames"] = backend.queued ? "queued" : "waited";
  out["warmup"] = args.warmup;
  out["repeat"] = args.repeat;
  out["tuning"] = tuning_json(base_tuning);  // before --tuning's sweep; each result has its own
  out["results"] = nlohmann::json::array();

  std::printf("%s: %zu Gaussians (SH degree %d, %s kernel) on %s; cameras", scene_path.c_str(), scene->size(),
              scene->sh_degree, kernel.description().c_str(), backend.name.c_str());
  for (int id : camera_ids) std::printf(" %d", id);
  std::printf("; %d warm-up + %d timed frames each, %s; per-camera medians, then median (p95) over cameras\n",
              args.warmup, args.repeat,
              backend.queued ? "queued back to back as the viewer renders them" : "each downloaded and waited for");
  const std::string changed = tuning_changes(base_tuning);
  if (!changed.empty()) std::printf("tuning (changed from the defaults): %s\n", changed.c_str());

  std::string table, uploads;
  for (std::size_t k = 0; k < resolutions.size(); ++k) {
    const std::string& resolution = args.resolutions[k];
    // One renderer per config, so each one's memory is its own high-water mark.
    std::vector<ConfigRun> runs;
    for (const RunConfig& config : configs) {
      ConfigRun r;
      r.name = config.name;
      r.options = config.options;
      r.tuning = config.tuning;
      r.renderer = create_backend(args.backend, args.threads, backend.cpu_blend, config.tuning);
      const auto upload_start = std::chrono::steady_clock::now();
      r.renderer->set_scene(scene);
      r.upload_ms = ms_since(upload_start);
      runs.push_back(std::move(r));
    }
    for (int id : camera_ids) {
      const Camera camera = all_cameras[id].resized(resolutions[k].width, resolutions[k].height);
      std::map<std::string, Image> baseline_of_kernel;  // by SplatKernel::spec()
      for (ConfigRun& r : runs) measure_camera(r, camera, id, args, backend.queued, baseline_of_kernel, runs.front().options);
      std::fprintf(stderr, "  %s camera %d done\n", resolution.c_str(), id);
    }
    for (const ConfigRun& r : runs) summarise(r, resolution, out["results"], table, uploads);
  }
  std::printf("%-10s %-28s %7s %7s %7s %7s %7s %8s %9s %9s %8s %7s %9s\n", "resolution", "config", "project", "emit",
              "sort", "ranges", "blend", "total", "(p95)", "kv", "peak MB", "PSNRmin", "max abs");
  std::printf("%s", table.c_str());
  std::printf("%s", uploads.c_str());
  write_file_atomically(args.json_path, out.dump(2) + "\n");
  std::printf("wrote %s\n", args.json_path.c_str());
}

}  // namespace

void register_bench(CLI::App& app) {
  auto args = std::make_shared<BenchArgs>();
  CLI::App* sub = app.add_subcommand("bench", "time every configuration over a camera set; table + JSON");
  args->scene.add_to(sub);
  sub->add_option("--backend", args->backend, "cpu, cuda or auto")->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  sub->add_option("--resolutions,-r", args->resolutions, "WxH list (comma separated)")->delimiter(',');
  sub->add_option("--configs", args->configs, "all, or names:" + known_config_names())->delimiter(',');
  // Taken whole, not split by CLI11, which drops empty items ("0,,1" would pass as "0,1").
  args->cameras_option = sub->add_option("--camera-list", args->cameras_text, "camera indices (default 0,2,...,34)");
  sub->add_option("--threads", args->threads, "CPU backend threads (0: every core)")->check(whole_number())->check(CLI::Range(0, 1024));
  sub->add_option("--cpu-blend", args->cpu_blend, "CPU backend blend kernel: simd, or scalar (the reference)")
      ->check(CLI::IsMember({"simd", "scalar"}));
  sub->add_option("--warmup", args->warmup, "untimed frames per camera and config")->check(whole_number())->check(CLI::NonNegativeNumber);
  sub->add_option("--repeat", args->repeat, "timed frames per camera and config")->check(whole_number())->check(CLI::PositiveNumber);
  sub->add_option("--frames", args->frames,
                  "queued (default: frames back to back, as the viewer renders them; GPU backends) or waited "
                  "(each frame downloaded and waited for, as render does)")
      ->check(CLI::IsMember({"queued", "waited"}));
  sub->add_option("--tile", args->copies, "render this many copies of the scene on a grid (scale runs)")
      ->check(whole_number())->check(CLI::Range(1, 4096));
  sub->add_option("--json,-o", args->json_path, "JSON output file");
  args->kernel.add_to(sub);
  args->tuning.add_to(sub);
  sub->callback([args] { run(*args); });
}

}  // namespace flashgs::cli
