// `flashgs lod build IN OUT`: a scene turned into a streamed LOD set; `flashgs lod city BASE OUT`:
// a city of instances of a set; `flashgs lod fly SET`: a set streamed along a camera path under
// memory caps, with frame times, stalls and memory.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <unistd.h>

#include "backend_factory.h"
#include "commands.h"
#include "finite_option.h"
#include "flashgs/compressed_formats.h"
#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "flashgs/io.h"
#include "flashgs/lod_build.h"
#include "flashgs/lod_city.h"
#include "flashgs/lod_feed.h"
#include "flashgs/lod_stream.h"
#include "flashgs/parse.h"
#include "flashgs/percentile.h"
#include "flashgs/renderer.h"
#include "flashgs/rotation.h"
#include "flashgs/scene_formats.h"
#include "option_checks.h"

namespace flashgs::cli {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

struct BuildArgs {
  std::string input, output;
  std::uint64_t leaf = 16384, file = 262144;
  int levels = 0;
  std::uint64_t memory_mb = 2048;
  int threads = 0;
  std::string chunk_format = "ply";
};

void run_build(const BuildArgs& args) {
  LodBuildOptions options;
  options.leaf_gaussians = args.leaf;
  options.file_gaussians = args.file;
  options.levels = args.levels;
  options.memory_bytes = args.memory_mb << 20;
  options.threads = args.threads;
  options.chunk_format = args.chunk_format == "sog" ? LodChunkFormat::sog : LodChunkFormat::ply;
  const bool tty = isatty(STDERR_FILENO);
  const char* last_stage = "";
  int last_percent = -1;
  options.progress = [&](const char* stage, std::uint64_t done, std::uint64_t total) {
    const int percent = total ? static_cast<int>(100.0 * static_cast<double>(done) / static_cast<double>(total)) : 100;
    if (std::string(stage) == last_stage && (percent == last_percent || (!tty && percent / 25 == last_percent / 25))) return;
    if (tty) std::fprintf(stderr, "\r%-9s %3d%% (%llu of %llu Gaussians)", stage, percent, static_cast<unsigned long long>(done),
                          static_cast<unsigned long long>(total));
    else std::fprintf(stderr, "%s %d%%\n", stage, percent);
    if (tty && percent == 100) std::fprintf(stderr, "\n");
    last_stage = stage;
    last_percent = percent;
  };
  const std::string input = locate_scene(args.input).ply;
  const auto t0 = Clock::now();
  const LodBuildReport r = build_lod_set(input, args.output, options);
  const double seconds = ms_between(t0, Clock::now()) / 1000.0;
  std::printf("built %s from %s: %llu Gaussians (%s), %d leaves, %d levels, %d chunk files, %.1f MB written, %.1f s\n",
              args.output.c_str(), input.c_str(), static_cast<unsigned long long>(r.gaussians),
              r.streamed ? "streamed from the disk" : "read whole", r.leaves, r.levels, r.files,
              static_cast<double>(r.bytes_written) / 1e6, seconds);
  for (std::size_t level = 0; level < r.level_gaussians.size(); ++level)
    std::printf("level %zu: %llu Gaussians\n", level, static_cast<unsigned long long>(r.level_gaussians[level]));
}

struct CityArgs {
  std::string base, output;
  LodCityOptions options;
  std::string chunk_format = "ply";
};

void run_city(CityArgs args) {
  args.options.chunk_format = args.chunk_format == "sog" ? LodChunkFormat::sog : LodChunkFormat::ply;
  const auto t0 = Clock::now();
  const LodCityReport r = write_lod_city(args.base, args.output, args.options);
  const double seconds = ms_between(t0, Clock::now()) / 1000.0;
  const float* lo = r.bound.min.data();
  const float* hi = r.bound.max.data();
  std::printf("city %s: %d blocks of %s (%d per row, %.2f apart), %.1f x %.1f x %.1f scene units; %d chunk files %s, "
              "%.1f MB of chunks as streamed, %.2f MB written, %.2f s\n",
              args.output.c_str(), r.blocks, args.base.c_str(), r.side, r.spacing, hi[0] - lo[0], hi[1] - lo[1],
              hi[2] - lo[2], r.files, args.options.materialize ? "written moved (a plain set)" : "named through the link base/",
              static_cast<double>(r.chunk_bytes) / 1e6, static_cast<double>(r.written_bytes) / 1e6, seconds);
  for (std::size_t level = 0; level < r.level_gaussians.size(); ++level)
    std::printf("level %zu: %llu Gaussians\n", level, static_cast<unsigned long long>(r.level_gaussians[level]));
}

// The path through `cameras` in their order, `steps` frames from each to the next: positions
// blended linearly, rotations by normalised quaternion blend.
std::vector<Camera> fly_path(const std::vector<Camera>& cameras, int steps, int width, int height) {
  std::vector<Camera> path;
  for (std::size_t i = 0; i + 1 < cameras.size(); ++i) {
    const Camera a = cameras[i].resized(width, height), b = cameras[i + 1].resized(width, height);
    double ra[9], rb[9], qa[4], qb[4];
    for (int k = 0; k < 9; ++k) ra[k] = a.rotation[k], rb[k] = b.rotation[k];
    quaternion_from_matrix(ra, qa);
    quaternion_from_matrix(rb, qb);
    if (qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3] < 0)
      for (double& c : qb) c = -c;
    for (int s = 0; s < steps; ++s) {
      const double t = static_cast<double>(s) / steps;
      Camera c = a;
      double q[4], n = 0;
      for (int k = 0; k < 4; ++k) {
        q[k] = (1 - t) * qa[k] + t * qb[k];
        n += q[k] * q[k];
      }
      for (double& v : q) v /= std::sqrt(n);
      double m[9];
      matrix_from_quaternion(q, m);
      for (int k = 0; k < 9; ++k) c.rotation[k] = static_cast<float>(m[k]);
      for (int k = 0; k < 3; ++k) c.position[k] = static_cast<float>((1 - t) * a.position[k] + t * b.position[k]);
      path.push_back(c);
    }
  }
  if (!cameras.empty()) path.push_back(cameras.back().resized(width, height));
  return path;
}

struct FlyArgs {
  std::string set, cameras, backend = "auto", resolution = "1280x720";
  int steps = 30, threads = 2;
  std::uint64_t budget = 0, host_mb = 0, gpu_mb = 0;
  float max_error_px = kDefaultLodMaxErrorPx;
  int psnr_every = 0;
  std::string frames_csv;  // one row per frame
  double fps = 60;  // the display's rate the flight keeps to: frames start no sooner than 1/fps apart
};

void run_fly(const FlyArgs& args) {
  if (!args.frames_csv.empty()) check_output_file("--frames-csv", args.frames_csv);  // before the flight, not after
  LodStreamOptions options;
  options.cut.budget = args.budget;
  options.cut.max_error_px = args.max_error_px;
  options.host_bytes = args.host_mb << 20;
  options.device_bytes = args.gpu_mb << 20;
  options.threads = args.threads;
  LodSet set = read_lod_set(args.set);
  const std::string cameras_path = args.cameras.empty() ? (std::filesystem::path(set.folder) / "cameras.json").string() : args.cameras;
  const std::vector<Camera> cameras = load_cameras(cameras_path);
  if (cameras.empty()) throw Error(cameras_path + ": holds no camera");
  const Resolution size = parse_resolution(args.resolution);
  const std::vector<Camera> path = fly_path(cameras, args.steps, size.width, size.height);
  std::unique_ptr<Renderer> renderer = create_backend(args.backend);
  std::unique_ptr<Renderer> reference_renderer;
  std::shared_ptr<const Scene> full;
  if (args.psnr_every > 0) {
    full = std::make_shared<Scene>(read_sog_lod(args.set, 0));
    reference_renderer = create_backend(args.backend);
    reference_renderer->set_scene(full);
  }
  const bool cpu = renderer->name().rfind("cpu", 0) == 0;
  lod_frame_costs(cpu ? BackendKind::cpu : BackendKind::cuda, size.width, size.height,
                  static_cast<int>(std::thread::hardware_concurrency()), &options.host_frame, &options.device_frame);
  // A GPU backend keeps the cut's parts in device memory and uploads only new ones; its frames
  // are queued and waited for, as the viewer shows them without a copy to the host. The CPU
  // backend assembles the parts into one scene.
  const bool gpu_parts = can_queue_frames(*renderer);
  options.parts_on_device = gpu_parts;
  LodStreamer streamer(std::move(set), options);
  LodCutFeed feed(streamer);
  const LodSet& lod = streamer.set();
  const std::string instances = lod.instances.empty() ? "" : " (" + std::to_string(lod.instances.size()) + " instances)";
  std::printf("set %s: %zu leaves%s, %d levels, level 0 %llu Gaussians; path of %zu frames at %dx%d through %zu cameras\n",
              lod.meta_path.c_str(), lod.leaves.size(), instances.c_str(), lod.level_count,
              static_cast<unsigned long long>(lod.gaussians(0)), path.size(), size.width, size.height, cameras.size());

  RenderOptions render_options;
  Image image, reference;
  std::vector<double> frame_ms, psnrs, settled_psnrs;
  std::string csv = "frame,ms,drawn,leaves_coarser,leaves_missing,worst_error_px,psnr_shown_db,psnr_settled_db\n";
  std::vector<std::uint64_t> drawn;
  std::uint64_t gpu_high_water = 0;  // the drawn parts' pool and the frame's buffers
  // The first view waits for its chunks, as a viewer shows its load progress; later frames never wait.
  const auto open_start = Clock::now();
  streamer.update_parts(path.front(), nullptr);
  streamer.wait_until_idle();
  std::printf("first view ready after %.2f s\n", ms_between(open_start, Clock::now()) / 1000.0);
  const auto start = Clock::now();
  double first_second_ms = 0, longest_after_first_second = 0;
  int missing_frames = 0, swaps = 0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(static_cast<double>(i) / args.fps)));
    const auto t0 = Clock::now();
    if (feed.update(path[i], *renderer)) ++swaps;
    const std::uint64_t drawn_now = feed.cut_gaussians();
    if (drawn_now > 0 && gpu_parts) {
      FrameStats frame_stats;
      render_queued(*renderer, path[i], render_options, &frame_stats);
      finish_queued_frames(*renderer);
      gpu_high_water = std::max(gpu_high_water, frame_stats.scene_device_bytes + frame_stats.device_memory_bytes);
    } else if (drawn_now > 0) {
      renderer->render(path[i], render_options, image, nullptr);
    }
    const auto t1 = Clock::now();
    const double ms = ms_between(t0, t1);
    frame_ms.push_back(ms);
    drawn.push_back(drawn_now);
    if (ms_between(start, t0) < 1000.0) first_second_ms = std::max(first_second_ms, ms);
    else longest_after_first_second = std::max(longest_after_first_second, ms);
    const LodStreamStats s = streamer.stats();
    missing_frames += s.leaves_missing > 0;
    for (const std::string& line : streamer.take_errors()) std::fprintf(stderr, "warning: %s\n", line.c_str());
    std::string shown_db, settled_db;
    if (reference_renderer && drawn_now > 0 && i % static_cast<std::size_t>(args.psnr_every) == 0) {
      // Not timed. The frame as shown (leaves still on their way drawn coarser), then the cut
      // itself: once its chunks are all in, the same view again. Waiting for them lets this
      // flight's later frames find more in memory than a flight without comparisons would.
      if (gpu_parts) renderer->render(path[i], render_options, image, nullptr);
      reference_renderer->render(path[i], render_options, reference, nullptr);
      psnrs.push_back(std::min(compare_images(image, reference).psnr_db, 999.0));
      streamer.wait_until_idle();
      feed.update(path[i], *renderer);
      renderer->render(path[i], render_options, image, nullptr);
      settled_psnrs.push_back(std::min(compare_images(image, reference).psnr_db, 999.0));
      shown_db = std::to_string(psnrs.back());
      settled_db = std::to_string(settled_psnrs.back());
    }
    csv += std::to_string(i) + "," + std::to_string(ms) + "," + std::to_string(drawn_now) + "," +
           std::to_string(s.leaves_coarser) + "," + std::to_string(s.leaves_missing) + "," + std::to_string(s.worst_error_px) +
           "," + shown_db + "," + settled_db + "\n";
  }
  const double seconds = ms_between(start, Clock::now()) / 1000.0;
  const LodStreamStats s = streamer.stats();
  std::vector<double> drawn_d(drawn.begin(), drawn.end());
  std::printf("frames %zu in %.2f s at up to %.0f fps: median %.2f ms, p99 %.2f ms, longest %.2f ms (%.2f ms in the first second)\n",
              frame_ms.size(), seconds, args.fps, percentile(frame_ms, 0.5), percentile(frame_ms, 0.99), longest_after_first_second,
              first_second_ms);
  std::printf("drawn Gaussians: median %.0f, max %.0f (budget after the caps: %s); scene swaps %d; frames with a leaf "
              "not yet in memory %d\n",
              percentile(drawn_d, 0.5), percentile(drawn_d, 1.0), s.budget ? std::to_string(s.budget).c_str() : "none", swaps,
              missing_frames);
  std::printf("host memory: high-water %.1f MiB of a %s cap; chunk bytes read %.1f MB (%.1f MB/s); files resident %d, failed %d\n",
              static_cast<double>(s.host_high_water) / (1 << 20),
              args.host_mb ? (std::to_string(args.host_mb) + " MiB").c_str() : "no",
              static_cast<double>(s.bytes_read) / 1e6, static_cast<double>(s.bytes_read) / 1e6 / seconds, s.files_resident,
              s.files_failed);
  if (gpu_parts)
    std::printf("GPU memory: high-water %.1f MiB (parts held and frame buffers) of a %s cap\n",
                static_cast<double>(gpu_high_water) / (1 << 20),
                args.gpu_mb ? (std::to_string(args.gpu_mb) + " MiB").c_str() : "no");
  // Identical frames have an infinite PSNR: held at 999 dB so that the order statistics stay defined.
  if (!psnrs.empty())
    std::printf("PSNR against the full-detail scene (%zu frames, 999: identical): as shown median %.2f dB, min %.2f dB; "
                "the cut settled median %.2f dB, min %.2f dB\n",
                psnrs.size(), percentile(psnrs, 0.5), percentile(psnrs, 0.0), percentile(settled_psnrs, 0.5),
                percentile(settled_psnrs, 0.0));
  if (!args.frames_csv.empty()) {
    write_file_atomically(args.frames_csv, csv);
    std::printf("wrote %s\n", args.frames_csv.c_str());
  }
}

}  // namespace

void register_lod(CLI::App& app) {
  CLI::App* lod = app.add_subcommand("lod", "build a streamed level-of-detail set, lay out a city of one, or fly through one");
  lod->require_subcommand(1);

  auto build = std::make_shared<BuildArgs>();
  CLI::App* b = lod->add_subcommand("build", "split a scene into spatial chunks with coarser merged levels (out of core)");
  b->add_option("IN", build->input, "the scene: any format the tool reads (binary PLY is streamed from the disk)")->required();
  b->add_option("OUT", build->output, "the folder to write lod-meta.json and the chunk files into (new or empty)")->required();
  b->add_option("--leaf-size", build->leaf, "Gaussians of a leaf cell at level 0, about")->check(whole_number())->check(CLI::Range(1, 1 << 26));
  b->add_option("--levels", build->levels, "levels (default: until about 256 Gaussians per leaf)")->check(whole_number())->check(CLI::Range(1, 16));
  b->add_option("--file-size", build->file, "Gaussians per chunk file, at most")->check(whole_number())->check(CLI::Range(1, 1 << 28));
  b->add_option("--memory", build->memory_mb, "MiB the builder may hold at once")->check(whole_number())->check(CLI::Range(16, 1 << 22));
  b->add_option("--threads", build->threads, "threads merging leaves (0: every core; the set is the same for any count)")
      ->check(whole_number())
      ->check(CLI::Range(0, 1024));
  b->add_option("--chunk-format", build->chunk_format,
                 "ply: INRIA PLY chunks at full precision (default); sog: SOG chunk folders (quantised, smaller), "
                 "which PlayCanvas's viewers stream")
      ->check(CLI::IsMember({"ply", "sog"}));
  b->callback([build] { run_build(*build); });

  auto city = std::make_shared<CityArgs>();
  CLI::App* c = lod->add_subcommand("city", "lay out a city of instances of a LOD set in seconds (the base's chunk files "
                                            "are named, not copied)");
  c->add_option("BASE", city->base, "the base set's lod-meta.json or its folder (a plain set)")->required();
  c->add_option("OUT", city->output, "the folder to write the city's lod-meta.json and cameras.json into (new or empty)")
      ->required();
  c->add_option("--blocks,-n", city->options.blocks, "blocks of the city, each an instance of the base")
      ->required()
      ->check(whole_number())
      ->check(CLI::Range(1, 65536));
  c->add_option("--spacing", city->options.spacing, "between block centres, in scene units (default: 1.1 x the base's width)")
      ->check(finite_in(1e-6, 1e9));
  c->add_option("--up", city->options.up, "the base's up axis (default +z)")
      ->check(CLI::IsMember({"+x", "-x", "+y", "-y", "+z", "-z"}));
  c->add_option("--cameras", city->options.path_cameras, "cameras of the fly-through written to cameras.json (default 60)")
      ->check(whole_number())
      ->check(CLI::Range(2, 10000));
  CLI::Option* materialize = c->add_flag(
      "--materialize", city->options.materialize,
      "write each block's chunks moved for real: a plain set without our instance keys, blocks x the base's bytes");
  c->add_option("--chunk-format", city->chunk_format,
                "with --materialize: ply (default) or sog (SOG chunk folders, which PlayCanvas's viewers stream)")
      ->check(CLI::IsMember({"ply", "sog"}))
      ->needs(materialize);
  c->callback([city] { run_city(*city); });

  auto fly = std::make_shared<FlyArgs>();
  CLI::App* f = lod->add_subcommand("fly", "stream a LOD set along a camera path and report frame times, stalls and memory");
  f->add_option("SET", fly->set, "the set's lod-meta.json or its folder")->required();
  f->add_option("--cameras", fly->cameras, "cameras.json whose cameras the path visits in order (default: beside the set)");
  f->add_option("--steps", fly->steps, "frames from one camera to the next")->check(whole_number())->check(CLI::Range(1, 10000));
  f->add_option("--resolution,-r", fly->resolution, "WxH")->check(resolution_text());
  f->add_option("--backend", fly->backend, "cpu | cuda | auto");
  f->add_option("--budget", fly->budget, "Gaussians drawn at most (default: no limit but the caps)")->check(whole_number());
  f->add_option("--max-error-px", fly->max_error_px, "detail bound: a leaf is refined while its error is larger")
      ->check(finite_in(0.0, 1e6));
  f->add_option("--host-memory", fly->host_mb, "MiB for chunks and drawn scenes (default: no cap)")->check(whole_number());
  f->add_option("--gpu-memory", fly->gpu_mb, "MiB of GPU memory for the drawn scene (default: no cap)")->check(whole_number());
  f->add_option("--fps", fly->fps, "the display rate the flight keeps to (frames start no sooner than 1/fps apart)")
      ->check(finite_in(0.1, 1000.0));
  f->add_option("--threads", fly->threads, "chunk loader threads")->check(whole_number())->check(CLI::Range(1, 64));
  f->add_option("--psnr-every", fly->psnr_every,
                 "compare every Nth frame with the full-detail scene held whole, as shown and with the cut settled (0: never)")
      ->check(whole_number());
  f->add_option("--frames-csv", fly->frames_csv, "write one row per frame: time, Gaussians drawn, leaves not at their level, PSNR");
  f->callback([fly] { run_fly(*fly); });
}

}  // namespace flashgs::cli
