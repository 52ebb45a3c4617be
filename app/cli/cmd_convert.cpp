// `flashgs convert IN OUT`: a scene in any format the tool reads, written in the format OUT's
// name picks, and what the conversion lost (read back and compared, images included).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "commands.h"
#include "conversion_loss.h"
#include "flashgs/error.h"
#include "flashgs/io.h"
#include "flashgs/scene_formats.h"
#include "option_checks.h"
#include "scene_source.h"

namespace flashgs::cli {
namespace {

// The width of the images the loss report compares (small: the CPU renders six of them).
constexpr int kLossImageWidth = 320;

struct ConvertArgs {
  std::string input;
  std::string output;
  bool force = false;
  int lod = -1;
  int sh_degree = 3;
  int spz_version = 3;
  std::string spz_axes = "niantic";
  bool no_loss = false;
};

namespace fs = std::filesystem;

SceneReadOptions read_options(const ConvertArgs& args) {
  SceneReadOptions options;
  parse_spz_axes(args.spz_axes, options.spz_axes);  // the option's check admits only valid values
  return options;
}

// Every check that needs no scene, so that a mistake costs no decoding.
const WritableFormat& check_paths(const ConvertArgs& args, const std::string& input_file) {
  const WritableFormat* format = writable_format_for(args.output);
  if (!format)
    throw Error("OUT " + args.output + ": unknown scene format (the name picks it: " + writable_scene_extensions() +
                ")");
  check_output_file("OUT", args.output);
  std::error_code ec;
  if (fs::exists(args.output, ec)) {
    if (fs::equivalent(input_file, args.output, ec))
      throw Error("OUT " + args.output + ": is the input file itself; name another output file");
    if (!args.force) throw Error("OUT " + args.output + ": already exists (give --force to overwrite it)");
  }
  return *format;
}

// The scene with at most `degree` SH bands.
Scene with_sh_degree(Scene scene, int degree) {
  if (scene.sh_degree <= degree) return scene;
  const int from = scene.sh_rest_per_gaussian();
  scene.sh_degree = degree;
  const int to = scene.sh_rest_per_gaussian();
  std::vector<float> rest;
  rest.reserve(scene.size() * static_cast<std::size_t>(to));
  for (std::size_t i = 0; i < scene.size(); ++i)
    rest.insert(rest.end(), scene.sh_rest.begin() + static_cast<std::ptrdiff_t>(i * from),
                scene.sh_rest.begin() + static_cast<std::ptrdiff_t>(i * from + to));
  scene.sh_rest.swap(rest);
  return scene;
}

// What the output format cannot hold, said before writing.
void print_notes(const WritableFormat& format, const Scene& scene, const std::string& input_file) {
  if (scene.sh_degree > format.max_sh_degree)
    std::fprintf(stderr, "note: %s has no SH bands beyond degree %d; degree %d of %s is reduced to it\n",
                 format_name(format.format), format.max_sh_degree, scene.sh_degree, input_file.c_str());
  const TrainedKernel& kernel = scene.trained_kernel;
  const bool flag_only = format.format == SceneFormat::spz || format.format == SceneFormat::sog ||
                         format.format == SceneFormat::sog_bundle;
  const bool epsilon_lost = flag_only && kernel.kernel.compensates_opacity() &&
                            kernel.kernel.epsilon != SplatKernel::antialiased().epsilon;
  if (kernel.kernel.compensates_opacity() && (!format.holds_kernel_mark || epsilon_lost))
    std::fprintf(stderr,
                 "note: %s cannot say which kernel a scene needs; %s is %s (from the %s): draw the output with "
                 "--kernel %s\n",
                 format_name(format.format), input_file.c_str(), kernel.kernel.description().c_str(),
                 kernel.source.c_str(), kernel.kernel.spec().c_str());
}

void run(const ConvertArgs& args) {
  const SceneLocation location = locate_scene(args.input);
  const WritableFormat& format = check_paths(args, location.ply);
  const SceneReadOptions options = read_options(args);
  LoadReport report;
  const Scene input = load_scene_at_level(location.ply, args.lod, &report, options);
  const Scene scene = with_sh_degree(input, std::min(args.sh_degree, format.max_sh_degree));
  print_notes(format, input, location.ply);
  if (const std::size_t negative = format.format == SceneFormat::inria_ply ? count_negative_scales(scene) : 0)
    std::fprintf(stderr,
                 "note: %zu of %zu Gaussians of %s have a negative scale, which PLY's log scales cannot hold; "
                 "written as its magnitude (the same ellipsoid)\n",
                 negative, scene.size(), location.ply.c_str());
  SceneWriteOptions write_options;
  write_options.spz_version = args.spz_version;
  write_options.spz_axes = options.spz_axes;
  format.write(scene, args.output, write_options);
  std::printf("read %s (%s, %zu Gaussians, SH degree %d, decoded in %.3f s), wrote %s (%s)\n", location.ply.c_str(),
              report.format.c_str(), input.size(), input.sh_degree, report.decode_seconds, args.output.c_str(),
              format_name(format.format));
  if (args.no_loss) return;
  // The output as any reader of it sees it: read back through the same entry point.
  const Scene back = load_scene_file(args.output, nullptr, nullptr, options);
  const ConversionLoss loss =
      measure_conversion_loss(input, scene, back, loss_views(input, location.cameras, kLossImageWidth));
  std::fputs(format_conversion_loss(loss).c_str(), stdout);
}

}  // namespace

void register_convert(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* sub = app.add_subcommand(
      "convert", "convert a scene to another format and print what the conversion loses");
  sub->add_option("IN", args->input, "the scene to read: any format the tool reads, or a scene folder")->required();
  sub->add_option("OUT", args->output,
                  "the file to write; its name picks the format: .ply, .compressed.ply, .splat, .spz, .sog (zipped "
                  "SOG) or meta.json (SOG, textures beside it)")
      ->required();
  sub->add_flag("--force", args->force, "overwrite OUT if it exists");
  sub->add_option("--lod", args->lod, kLodOptionHelp)->check(whole_number())->check(CLI::NonNegativeNumber);
  sub->add_option("--sh-degree", args->sh_degree, "write at most this many SH bands")
      ->check(whole_number())
      ->check(CLI::Range(0, 3));
  sub->add_option("--spz-version", args->spz_version, "SPZ version to write: 3 (gzip) or 4 (zstd)")
      ->check(CLI::IsMember({3, 4}));
  sub->add_option("--spz-axes", args->spz_axes,
                  "axes of SPZ files read and written: niantic (right-up-back, Niantic's spz library) or none "
                  "(PLY's axes unchanged, as some converters wrote)")
      ->check(CLI::IsMember({"niantic", "none"}));
  sub->add_flag("--no-loss", args->no_loss, "skip reading OUT back and comparing it with IN");
  sub->callback([args] { run(*args); });
}

}  // namespace flashgs::cli
