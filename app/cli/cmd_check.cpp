// `flashgs check`: every stress case, on every backend present, with both algorithms, judged
// against the fp64 reference; prints a table and exits non-zero when a case fails.
#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "backend_factory.h"
#include "commands.h"
#include "flashgs/error.h"
#include "flashgs/file_write.h"
#include "flashgs/image_io.h"
#include "flashgs/stress_check.h"
#include "kernel_option.h"
#include "flashgs/stress_scenes.h"
#include "option_checks.h"

namespace flashgs::cli {
namespace {

struct CheckArgs {
  std::vector<std::string> cases;  // empty: all (huge ones only with --huge)
  bool huge = false;
  std::string backend = "all";
  std::string csv;
  std::string images_dir;
  bool explain = false;
  std::string kernel = "both";  // both, or one kernel
};

// The kernels --kernel names: classic and gsplat's anti-aliased one for "both".
std::vector<SplatKernel> kernels_of(const std::string& text) {
  if (text == "both") return {SplatKernel::classic(), SplatKernel::antialiased()};
  return {parse_splat_kernel(text, "--kernel")};
}

struct Backend {
  std::string name;
  std::unique_ptr<Renderer> renderer;
};

std::vector<Backend> present_backends(const std::string& which) {
  std::vector<Backend> out;
  for (const char* name : {"cpu", "cuda"}) {
    if (which != "all" && which != name) continue;
    try {
      out.push_back({name, create_backend(name)});
    } catch (const Error& e) {
      if (which == name) throw;
      std::fprintf(stderr, "note: backend %s not checked: %s\n", name, e.what());
    }
  }
  return out;
}

// printf onto the end of `out`.
__attribute__((format(printf, 2, 3))) void append_format(std::string& out, const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list again;
  va_copy(again, args);
  const int size = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  if (size > 0) {
    const std::size_t old_size = out.size();
    out.resize(old_size + static_cast<std::size_t>(size) + 1);
    std::vsnprintf(&out[old_size], static_cast<std::size_t>(size) + 1, format, again);
    out.resize(old_size + static_cast<std::size_t>(size));
  }
  va_end(again);
}

// Case `c` with one kernel on every backend, both algorithms: prints its rows (and adds them to
// `csv` when given, writes its images) and returns the failures.
int check_case(const StressCase& c, const std::shared_ptr<const Scene>& scene, const SplatKernel& kernel,
               std::vector<Backend>& backends, const CheckArgs& args, std::string* csv) {
  const std::string& name = c.name;
  int failures = 0;
  const StressReference reference = render_stress_reference(c, kernel);
  for (Backend& backend : backends) {
    backend.renderer->set_scene(scene);
    // On the CPU the image must also not depend on how the work is split: one thread too.
    std::unique_ptr<Renderer> single;
    if (backend.name == "cpu" && !c.huge) {
      single = make_cpu_renderer(1);
      single->set_scene(scene);
    }
    for (Algorithm algorithm : {Algorithm::flash, Algorithm::baseline}) {
      std::vector<Image> images;
      const StressResult r = run_stress_case(c, reference, *backend.renderer, backend.name, algorithm, single.get(),
                                             args.images_dir.empty() || c.huge ? nullptr : &images, kernel);
      failures += r.pass ? 0 : 1;
      std::string result = r.pass ? "pass" : "FAIL " + r.why_failed;
      if (!r.ran && r.pass) result = "pass (refused: " + r.error + ")";
      std::printf("%-16s %-11s %-5s %-8s %7llu %11.3e %9.2e %6s %10llu %9.2f  %s\n", name.c_str(), r.kernel.c_str(),
                  backend.name.c_str(), r.algorithm.c_str(), static_cast<unsigned long long>(r.non_finite),
                  r.max_abs_error, r.bound, r.deterministic ? "yes" : "NO", static_cast<unsigned long long>(r.kv_pairs),
                  r.milliseconds, result.c_str());
      std::fflush(stdout);
      if (csv)
        append_format(*csv, "%s,%s,%s,%s,%d,%llu,%.6e,%.6e,%d,%llu,%.3f,%d,\"%s\"\n", name.c_str(), r.kernel.c_str(),
                      backend.name.c_str(), r.algorithm.c_str(), r.ran ? 1 : 0,
                      static_cast<unsigned long long>(r.non_finite), r.max_abs_error, r.bound, r.deterministic ? 1 : 0,
                      static_cast<unsigned long long>(r.kv_pairs), r.milliseconds, r.pass ? 1 : 0,
                      (r.why_failed + r.error).c_str());
      for (std::size_t k = 0; k < images.size(); ++k)
        write_image(images[k], args.images_dir + "/" + name + "_" + r.kernel + "_" + backend.name + "_" +
                                   r.algorithm + "_cam" + std::to_string(k) + ".png");
    }
  }
  std::printf("%-16s %-11s fp64 reference: %.2f s%s\n", name.c_str(), kernel.spec().c_str(), reference.seconds,
              c.windows.empty() ? " (whole image)" : " (windows of the image)");
  return failures;
}

int run(const CheckArgs& args) {
  const std::vector<SplatKernel> kernels = kernels_of(args.kernel);
  // The case names, then the output paths, all before the first case: a failure after the cases
  // have run would waste minutes. make_stress_case's message names the case and the known ones.
  const std::vector<std::string> known = stress_case_names();
  for (const std::string& name : args.cases)
    if (std::find(known.begin(), known.end(), name) == known.end()) make_stress_case(name);
  if (!args.csv.empty()) check_output_file("--csv", args.csv);
  if (!args.images_dir.empty()) check_output_folder("--images", args.images_dir);
  std::vector<std::string> names = args.cases;
  if (names.empty())
    for (const std::string& name : stress_case_names()) {
      if (!args.huge && make_stress_case(name).huge) continue;
      names.push_back(name);
    }
  std::vector<Backend> backends = present_backends(args.backend);
  // The CSV is written whole once every case has run (write_file_atomically).
  std::string csv_text = "case,kernel,backend,algorithm,ran,nan_inf,max_abs_error,bound,deterministic,kv_pairs,ms,pass,note\n";
  std::string* csv = args.csv.empty() ? nullptr : &csv_text;
  std::printf("%-16s %-11s %-5s %-8s %7s %11s %9s %6s %10s %9s  %s\n", "case", "kernel", "back", "algo", "nan/inf",
              "max|err|", "bound", "determ", "kv pairs", "ms", "result");
  int failures = 0;
  std::vector<std::pair<std::string, std::string>> reasons;
  for (const std::string& name : names) {
    StressCase c = make_stress_case(name);
    const LoadReport report = load_stress_scene(c);
    if (!c.raw_ply.empty())
      std::printf("%-16s load_ply kept %zu of %zu: dropped %zu non-finite, repaired %zu zero quaternions\n",
                  name.c_str(), c.scene.size(), report.vertices_in_file, report.dropped_non_finite,
                  report.repaired_zero_quaternion);
    auto scene = std::make_shared<const Scene>(c.scene);
    reasons.push_back({name, c.bound_reason});
    for (const SplatKernel& kernel : kernels) failures += check_case(c, scene, kernel, backends, args, csv);
  }
  if (csv) write_file_atomically(args.csv, csv_text);
  if (args.explain) {
    std::printf("\nbounds (max |image - fp64 reference|), why:\n");
    for (const auto& [name, why] : reasons) std::printf("  %-16s %s\n", name.c_str(), why.c_str());
  }
  std::printf("%s: %d failure(s)\n", failures ? "FAILED" : "all passed", failures);
  return failures ? 1 : 0;
}

}  // namespace

void register_check(CLI::App& app) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* sub = app.add_subcommand(
      "check", "render every stress case on every backend, both algorithms, against the fp64 reference");
  sub->add_option("--case", args->cases, "only these cases (repeatable); see `flashgs generate stress --list`");
  sub->add_flag("--huge", args->huge, "include the 8192^2 and 16384^2 image cases");
  sub->add_option("--backend", args->backend, "all (every backend present), cpu or cuda")
      ->check(CLI::IsMember({"all", "cpu", "cuda"}));
  sub->add_option("--csv", args->csv, "also write the table as CSV");
  sub->add_option("--images", args->images_dir, "write each rendered image (PNG) into this folder");
  sub->add_flag("--explain", args->explain, "print why each bound is what it is");
  sub->add_option("--kernel", args->kernel, "both (classic and antialiased), or one: classic, antialiased[=EPS]")
      ->check(kernel_validator("both"));
  sub->callback([args] {
    const int failures = run(*args);
    if (failures) throw CLI::RuntimeError(1);
  });
}

}  // namespace flashgs::cli
