// `flashgs report`: sweeps the configurations (baseline, flash, each optimisation alone and left
// out, tau up to 1/16, the GPU switches on CUDA) on every backend present, and writes a CSV, a
// Markdown table and an SVG plot of error against run time with the Pareto front marked.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "backend_factory.h"
#include "commands.h"
#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/file_write.h"
#include "flashgs/io.h"
#include "flashgs/parse.h"
#include "flashgs/reference_renderer.h"
#include "flashgs/scene_summary.h"
#include "option_checks.h"
#include "report_plot.h"
#include "report_sweep.h"
#include "scene_source.h"
#include "tuning_options.h"

namespace flashgs::cli {
namespace {

struct ReportArgs {
  SceneArgs scene;
  std::string camera_list_text;  // --camera-list as typed
  CLI::Option* camera_list_option = nullptr;
  int max_cameras = 0;      // 0: all of the list
  std::string resolution;
  int repeat = 3;
  std::string backend = "all";
  int ref_window = 64;
  int ref_cameras = 3;
  std::string output_dir = "report";
  std::string title;
  std::string replot;    // re-plot this report.csv instead of measuring
  std::string subtitle;  // for --replot
  KernelOption kernel;   // the kernel every configuration but the kernel group's draws with
  TuningOptions tuning;  // every configuration runs once per tuning variant
};

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown CPU";
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string psnr_text(double db) { return std::isfinite(db) ? fmt("%.1f", db) : "inf"; }
// The CSV keeps more digits, so that --replot finds the same Pareto front.
std::string psnr_csv(double db) { return std::isfinite(db) ? fmt("%.4f", db) : "inf"; }

// What a report writes into its folder, checked before anything is measured.
constexpr const char* kReportFiles[] = {"report.csv", "report.md", "report_cpu.svg", "report_cuda.svg"};

// A report.csv holds a row per configuration and backend: a few kB.
constexpr std::size_t kMaxReportCsvBytes = std::size_t{64} << 20;

// Re-plots a report.csv (written by an earlier run) without measuring again.
void replot(const ReportArgs& args) {
  // Checked and read without blocking: a FIFO or a folder is one line, not a hang.
  const std::vector<char> text = read_regular_file(args.replot, kMaxReportCsvBytes);
  std::istringstream in(std::string(text.begin(), text.end()));
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  {
    std::stringstream h(line);
    std::string cell;
    while (std::getline(h, cell, ',')) header.push_back(cell);
  }
  auto column = [&](const std::string& name) {
    for (std::size_t k = 0; k < header.size(); ++k)
      if (header[k] == name) return k;
    throw Error(args.replot + ": no column \"" + name + "\"");
  };
  const std::size_t c_backend = column("backend"), c_config = column("config"), c_group = column("group"),
                    c_median = column("median_ms"), c_p95 = column("p95_ms"), c_psnr = column("psnr_vs_fp64_db");
  std::vector<SweepResult> results;
  int line_number = 1;
  auto number = [&](const std::string& cell) {
    if (cell == "inf") return static_cast<double>(INFINITY);
    char* end = nullptr;
    const double v = std::strtod(cell.c_str(), &end);
    if (cell.empty() || *end != '\0' || std::isnan(v))
      throw Error(args.replot + ": line " + std::to_string(line_number) + ": \"" + cell + "\" is not a number");
    return v;
  };
  while (std::getline(in, line)) {
    ++line_number;
    std::vector<std::string> cells;
    std::stringstream row(line);
    std::string cell;
    while (std::getline(row, cell, ',')) cells.push_back(cell);
    if (cells.size() < header.size()) continue;
    SweepResult r;
    r.backend = cells[c_backend];
    r.config.name = cells[c_config];
    r.config.group = cells[c_group];
    r.median_ms = number(cells[c_median]);
    r.p95_ms = number(cells[c_p95]);
    r.vs_reference.psnr_db = number(cells[c_psnr]);
    results.push_back(r);
  }
  const std::string dir = std::filesystem::path(args.replot).parent_path().string();
  for (const std::string& bname : {std::string("cpu"), std::string("cuda")}) {
    std::vector<SweepResult> subset;
    for (const SweepResult& r : results)
      if (r.backend == bname) subset.push_back(r);
    if (subset.empty()) continue;
    const std::string path = (dir.empty() ? std::string(".") : dir) + "/report_" + bname + ".svg";
    const std::string title = args.title.empty() ? std::string("report") : args.title;
    write_file_atomically(path, plot_svg(subset, "Error vs run time: " + title + " (" + bname + ")", args.subtitle));
    std::printf("wrote %s\n", path.c_str());
  }
}

// The report into the checked output folder.
// --camera-list (or 0, 2, ..., 34 as far as the file has them), cut to --max-cameras.
std::vector<int> report_camera_ids(const ReportArgs& args, std::size_t camera_count, const std::string& cameras_path) {
  const bool listed = args.camera_list_option->count() > 0;
  std::vector<int> kept = listed ? parse_index_list("--camera-list", args.camera_list_text) : std::vector<int>{};
  if (!listed) {
    // The default list (the views of ANCHORS.md), as far as the file has them.
    for (int i = 0; i <= 34 && i < static_cast<int>(camera_count); i += 2) kept.push_back(i);
    if (kept.empty()) throw Error(cameras_path + ": holds no camera");
  }
  check_camera_indices("--camera-list", kept, camera_count, cameras_path);
  if (args.max_cameras > 0 && static_cast<int>(kept.size()) > args.max_cameras) kept.resize(args.max_cameras);
  return kept;
}

using NamedBackends = std::vector<std::pair<std::string, std::unique_ptr<Renderer>>>;

// The backends --backend asks for (all: every one present, a missing one noted).
NamedBackends report_backends(const ReportArgs& args, const BackendTuning& tuning) {
  NamedBackends backends;
  for (const char* name : {"cpu", "cuda"}) {
    if (args.backend != "all" && args.backend != name) continue;
    try {
      backends.emplace_back(name, create_backend(name, 0, CpuBlend::simd, tuning));
    } catch (const Error& e) {
      if (args.backend == name) throw;
      std::fprintf(stderr, "note: backend %s not measured: %s\n", name, e.what());
    }
  }
  return backends;
}

// fp64 reference windows: the centre and two off-centre squares of side `side`. The reference
// costs pixels x Gaussians, so it is evaluated on these windows of the first few cameras only.
// Returns the seconds it took.
double add_reference(const Scene& scene, const SplatKernel& kernel, int side, std::size_t ref_cameras, SweepFrames& frames) {
  const int width = frames.cameras[0].width, height = frames.cameras[0].height;
  auto window_at = [&](double fx, double fy) {
    PixelWindow w;
    w.width = w.height = side;
    w.x0 = std::clamp(static_cast<int>(fx * width) - side / 2, 0, width - side);
    w.y0 = std::clamp(static_cast<int>(fy * height) - side / 2, 0, height - side);
    return w;
  };
  frames.windows = {window_at(0.5, 0.5), window_at(0.35, 0.6), window_at(0.65, 0.4)};
  const auto ref_start = std::chrono::steady_clock::now();
  RenderOptions ref_options;
  ref_options.kernel = kernel;
  for (std::size_t c = 0; c < ref_cameras; ++c) {
    std::vector<Image> per_window;
    for (const PixelWindow& w : frames.windows) per_window.push_back(render_reference(scene, frames.cameras[c], ref_options, w));
    frames.reference.push_back(std::move(per_window));
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - ref_start).count();
}

// Every configuration of the sweep on every backend, once per tuning variant, each on a fresh
// renderer.
std::vector<SweepResult> sweep(NamedBackends& backends, const std::shared_ptr<const Scene>& scene, const SplatKernel& kernel,
                               const std::vector<TuningVariant>& variants, SweepFrames& frames, int repeat,
                               std::vector<std::string>& backend_names) {
  std::vector<SweepResult> results;
  for (auto& [name, renderer] : backends) {
    renderer->set_scene(scene);
    backend_names.push_back(name + ": " + renderer->name());
    const bool gpu = name == "cuda";
    for (const SweepConfig& config : sweep_configs(kernel)) {
      if (config.gpu_only && !gpu) continue;  // the CPU ignores these switches
      for (const TuningVariant& variant : variants) {
        const auto start = std::chrono::steady_clock::now();
        // A fresh backend per configuration: its buffers only grow, so the peak memory of one
        // that rendered the baseline first would be the baseline's for every configuration.
        std::unique_ptr<Renderer> fresh = create_backend(name, 0, CpuBlend::simd, variant.tuning);
        fresh->set_scene(scene);
        SweepConfig named = config;
        named.name = with_tuning_label(config.name, variant);
        SweepResult r = measure_config(*fresh, name, named, frames, repeat);
        std::fprintf(stderr, "%-5s %-22s median %9.3f ms  p95 %9.3f ms  kv %11.0f  vs baseline %6s dB  vs fp64 %6s dB (%.0f s)\n",
                     name.c_str(), named.name.c_str(), r.median_ms, r.p95_ms, r.kv_pairs,
                     psnr_text(r.vs_baseline.psnr_db).c_str(), psnr_text(r.vs_reference.psnr_db).c_str(),
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        results.push_back(std::move(r));
      }
    }
  }
  return results;
}

std::vector<SweepResult> results_of(const std::vector<SweepResult>& results, const std::string& backend) {
  std::vector<SweepResult> subset;
  for (const SweepResult& r : results)
    if (r.backend == backend) subset.push_back(r);
  return subset;
}

// report.csv: one row per (backend, configuration), one column per switch.
void write_csv(const std::vector<SweepResult>& results, const std::string& path) {
  std::ostringstream csv;
  // One column per switch (its label token): 1 where it is in effect.
  csv << "backend,config,group,algorithm,";
  for (const RenderSwitch& s : kRenderSwitches) csv << s.label << ',';
  csv << "tau,fp16_sh,fp16_shape,fp16_blend,median_ms,p95_ms,frames,kv_pairs,peak_memory_mb,psnr_vs_baseline_db,"
         "max_abs_vs_baseline,frac_over_1_255_vs_baseline,psnr_vs_fp64_db,max_abs_vs_fp64,frac_over_1_255_vs_fp64,"
         "non_finite,pareto\n";
  for (const std::string& bname : {std::string("cpu"), std::string("cuda")}) {
    const std::vector<SweepResult> subset = results_of(results, bname);
    const std::vector<std::size_t> front = pareto_front(subset);
    for (std::size_t i = 0; i < subset.size(); ++i) {
      const SweepResult& r = subset[i];
      const RenderOptions& o = r.config.options;
      csv << r.backend << ',' << r.config.name << ',' << r.config.group << ',' << algorithm_name(o.algorithm) << ',';
      for (const RenderSwitch& s : kRenderSwitches) csv << (!o.is_baseline() && o.*(s.member)) << ',';
      csv << fmt("%.6g", o.tau) << ',' << o.fp16_sh << ',' << o.fp16_shape << ',' << o.fp16_blend << ','
          << fmt("%.4f", r.median_ms) << ',' << fmt("%.4f", r.p95_ms) << ',' << r.frame_ms.size() << ','
          << fmt("%.0f", r.kv_pairs) << ',' << (r.peak_memory_mb >= 0 ? fmt("%.1f", r.peak_memory_mb) : "") << ','
          << psnr_csv(r.vs_baseline.psnr_db) << ',' << fmt("%.3e", r.vs_baseline.max_abs) << ','
          << fmt("%.3e", r.vs_baseline.fraction_over) << ',' << psnr_csv(r.vs_reference.psnr_db) << ','
          << fmt("%.3e", r.vs_reference.max_abs) << ',' << fmt("%.3e", r.vs_reference.fraction_over) << ','
          << (r.vs_baseline.non_finite + r.vs_reference.non_finite) << ','
          << (std::find(front.begin(), front.end(), i) != front.end()) << '\n';
    }
  }
  write_file_atomically(path, csv.str());
}

// What report.md says about the run above its table.
struct ReportContext {
  std::string scene_path, title, camera_text;
  const Scene* scene = nullptr;
  SplatKernel kernel;
  int width = 0, height = 0, window_side = 0;
  std::size_t windows = 0, ref_cameras = 0;
  double ref_seconds = 0;
  std::vector<std::string> backend_names;
  std::string tuning;  // the values every run used (before --tuning's sweep)
};

// report.md and one plot per backend, report_<backend>.svg.
void write_markdown_and_plots(const ReportArgs& args, const ReportContext& c, const std::vector<SweepResult>& results,
                              const std::string& stem) {
  std::ostringstream md;
  md << "# flashgs report: " << c.title << "\n\n";
  md << "- scene: `" << c.scene_path << "`, " << c.scene->size() << " Gaussians, SH degree " << c.scene->sh_degree
     << ", drawn with the " << c.kernel.description() << " kernel ("
     << (args.kernel.chosen() ? std::string("--kernel") : kernel_summary(c.scene->trained_kernel)) << ")\n";
  md << "- cameras " << c.camera_text << " at " << c.width << "x" << c.height << "; per camera one warm-up frame, then "
     << args.repeat << " timed frames; time is the backend's FrameStats total (CPU: wall time of the stages)\n";
  md << "- host: " << cpu_model() << ", " << std::thread::hardware_concurrency() << " hardware threads\n";
  for (const std::string& b : c.backend_names) md << "- backend " << b << "\n";
  md << "- tuning (docs/TUNING.md): " << c.tuning << "\n";
  md << "- error vs baseline: whole frames against the same backend's baseline render; error vs fp64: the fp64 "
        "brute-force reference (cost pixels x Gaussians) on "
     << c.windows << " windows of " << c.window_side << "x" << c.window_side
     << " px (centre, (0.35, 0.6), (0.65, 0.4) of the "
     << "frame) of the first " << c.ref_cameras << " camera(s), " << fmt("%.0f", c.ref_seconds) << " s\n";
  md << "- peak MB: the backend's working memory above the scene (high-water mark of a backend created for that "
        "configuration); \"-\": not reported (CPU)\n";
  md << "- PSNR with peak 1.0 on float images; \"> 1/255\": fraction of pixels with a channel off by more than 1/255; "
        "kv: Gaussian-tile pairs per frame\n\n";
  md << "| backend | configuration | median ms | p95 ms | kv pairs | peak MB | PSNR vs baseline | max abs vs baseline | "
        "> 1/255 vs baseline | PSNR vs fp64 | max abs vs fp64 | > 1/255 vs fp64 | Pareto |\n";
  md << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> plots;
  for (const std::string& bname : {std::string("cpu"), std::string("cuda")}) {
    const std::vector<SweepResult> subset = results_of(results, bname);
    if (subset.empty()) continue;
    const std::vector<std::size_t> front = pareto_front(subset);
    for (std::size_t i = 0; i < subset.size(); ++i) {
      const SweepResult& r = subset[i];
      md << "| " << r.backend << " | " << r.config.name << " | " << fmt("%.3f", r.median_ms) << " | "
         << fmt("%.3f", r.p95_ms) << " | " << fmt("%.0f", r.kv_pairs) << " | "
         << (r.peak_memory_mb >= 0 ? fmt("%.1f", r.peak_memory_mb) : "-") << " | "
         << psnr_text(r.vs_baseline.psnr_db) << " | " << fmt("%.2e", r.vs_baseline.max_abs) << " | "
         << fmt("%.4f%%", 100 * r.vs_baseline.fraction_over) << " | " << psnr_text(r.vs_reference.psnr_db) << " | "
         << fmt("%.2e", r.vs_reference.max_abs) << " | " << fmt("%.4f%%", 100 * r.vs_reference.fraction_over) << " | "
         << (std::find(front.begin(), front.end(), i) != front.end() ? "yes" : "") << " |\n";
    }
    std::string device;
    for (const auto& b : c.backend_names)
      if (b.rfind(bname + ":", 0) == 0) device = b.substr(bname.size() + 2);
    const std::string subtitle = std::to_string(c.scene->size()) + " Gaussians, " + std::to_string(c.width) + "x" +
                                 std::to_string(c.height) + ", cameras " + c.camera_text + ", " + device +
                                 (bname == "cpu" ? " on " + cpu_model() : "");
    const std::string svg_path = stem + "_" + bname + ".svg";
    write_file_atomically(svg_path, plot_svg(subset, "Error vs run time: " + c.title + " (" + bname + ")", subtitle));
    plots.push_back("report_" + bname + ".svg");
    std::printf("wrote %s\n", svg_path.c_str());
  }
  md << "\nPlots (error vs median frame time, one point per configuration, Pareto front marked):";
  for (const std::string& p : plots) md << " [" << p << "](" << p << ")";
  md << "\n";
  write_file_atomically(stem + ".md", md.str());
}

void measure(const ReportArgs& args) {
  for (const char* name : kReportFiles) check_output_file("--output-dir", args.output_dir + "/" + name);
  const Resolution size = args.resolution.empty() ? Resolution{} : parse_resolution(args.resolution);
  ReportContext context;
  const std::vector<TuningVariant> variants = args.tuning.variants();
  context.tuning = tuning_summary(args.tuning.base());
  if (variants.size() > 1) context.tuning += "; each configuration also with " + std::to_string(variants.size()) +
                                             " settings of --tuning (named in its row)";
  context.scene_path = args.scene.resolved_scene();
  auto scene = load_scene_verbose(context.scene_path, args.scene.lod, args.scene.read_options());
  context.scene = scene.get();
  const std::string cameras_path = args.scene.resolved_cameras();
  const std::vector<Camera> all_cameras = load_cameras(cameras_path);
  const std::vector<int> kept = report_camera_ids(args, all_cameras.size(), cameras_path);
  SweepFrames frames;
  for (int i : kept) {
    Camera c = all_cameras[i];
    if (!args.resolution.empty()) c = c.resized(size.width, size.height);
    frames.cameras.push_back(c);
  }
  NamedBackends backends = report_backends(args, args.tuning.base());
  for (auto& [name, renderer] : backends)
    check_frame_fits(*renderer, frames.cameras.front(), scene->size(),
                     args.resolution.empty() ? "the cameras' size" : "--resolution");
  context.width = frames.cameras[0].width;
  context.height = frames.cameras[0].height;
  context.window_side = std::min({args.ref_window, context.width, context.height});
  context.ref_cameras = std::min<std::size_t>(std::max(0, args.ref_cameras), frames.cameras.size());
  context.kernel = args.kernel.resolve(*scene);
  context.ref_seconds = add_reference(*scene, context.kernel, context.window_side, context.ref_cameras, frames);
  context.windows = frames.windows.size();
  std::fprintf(stderr, "fp64 reference: %zu cameras x %zu windows of %dx%d in %.1f s\n", context.ref_cameras,
               context.windows, context.window_side, context.window_side, context.ref_seconds);

  const std::vector<SweepResult> results =
      sweep(backends, scene, context.kernel, variants, frames, args.repeat, context.backend_names);
  const std::string stem = args.output_dir + "/report";
  write_csv(results, stem + ".csv");
  context.title = args.title.empty() ? std::filesystem::path(context.scene_path).parent_path().filename().string()
                                     : args.title;
  for (int i : kept) context.camera_text += (context.camera_text.empty() ? "" : ", ") + std::to_string(i);
  write_markdown_and_plots(args, context, results, stem);
  std::printf("wrote %s.csv and %s.md\n", stem.c_str(), stem.c_str());
}

void run(const ReportArgs& args) {
  if (!args.replot.empty()) return replot(args);
  // Everything that can be wrong with the arguments is found before the first frame; a
  // folder made for the report goes again when anything fails (a missing scene, a bad camera).
  const std::vector<std::string> created = check_output_folder("--output-dir", args.output_dir);
  try {
    measure(args);
  } catch (...) {
    remove_created_folders(created);
    throw;
  }
}

}  // namespace

void register_report(CLI::App& app) {
  auto args = std::make_shared<ReportArgs>();
  CLI::App* sub = app.add_subcommand(
      "report", "sweep configurations (error vs run time): CSV, Markdown table and SVG plot with the Pareto front");
  args->scene.add_to(sub);
  // Taken whole, not split by CLI11, which drops empty items ("0,,1" would pass as "0,1").
  args->camera_list_option =
      sub->add_option("--camera-list", args->camera_list_text, "camera indices, e.g. 0,2,4 (default 0,2,...,34)");
  sub->add_option("--max-cameras", args->max_cameras, "use only the first N cameras of the list")
      ->check(whole_number())->check(CLI::NonNegativeNumber);
  sub->add_option("--resolution,-r", args->resolution, "render size WxH (field of view kept)")->check(resolution_text());
  sub->add_option("--repeat", args->repeat, "timed frames per camera (after one warm-up)")->check(whole_number())->check(CLI::Range(1, 1000));
  sub->add_option("--backend", args->backend, "all (every backend present), cpu or cuda")
      ->check(CLI::IsMember({"all", "cpu", "cuda"}));
  sub->add_option("--ref-window", args->ref_window, "side of the fp64 reference windows (px)")->check(whole_number())->check(CLI::Range(1, 4096));
  sub->add_option("--ref-cameras", args->ref_cameras, "cameras on which the fp64 reference is evaluated")
      ->check(whole_number())->check(CLI::Range(0, 1000));
  sub->add_option("--output-dir,-o", args->output_dir, "folder for report.csv, report.md, report_<backend>.svg");
  sub->add_option("--title", args->title, "title of the table and plots (default: the scene's folder name)");
  sub->add_option("--replot", args->replot, "only redraw the SVG plot(s) from this report.csv (beside it)");
  sub->add_option("--subtitle", args->subtitle, "with --replot: the plot's second line");
  args->kernel.add_to(sub);
  args->tuning.add_to(sub);
  sub->callback([args] { run(*args); });
}

}  // namespace flashgs::cli
