// `flashgs convert IN OUT`: a scene in any format the tool reads, written as INRIA PLY or .splat.
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "commands.h"
#include "flashgs/error.h"
#include "flashgs/io.h"
#include "flashgs/scene_formats.h"
#include "option_checks.h"

namespace flashgs::cli {
namespace {

struct ConvertArgs {
  std::string input;
  std::string output;
  bool force = false;
};

namespace fs = std::filesystem;

// Every check that needs no scene, so that a mistake costs no decoding.
void check_paths(const ConvertArgs& args, const std::string& input_file) {
  if (!scene_writer_for(args.output))
    throw Error("OUT " + args.output + ": unknown scene format (the extension picks it: " +
                writable_scene_extensions() + ")");
  check_output_file("OUT", args.output);
  std::error_code ec;
  if (fs::exists(args.output, ec)) {
    if (fs::equivalent(input_file, args.output, ec))
      throw Error("OUT " + args.output + ": is the input file itself; name another output file");
    if (!args.force) throw Error("OUT " + args.output + ": already exists (give --force to overwrite it)");
  }
}

void run(const ConvertArgs& args) {
  const std::string input_file = locate_scene(args.input).ply;
  check_paths(args, input_file);
  LoadReport report;
  const Scene scene = load_scene_file(input_file, &report);
  const SceneWriter write = scene_writer_for(args.output);
  if (write == save_splat && scene.sh_degree > 0)
    std::fprintf(stderr, "note: .splat has no SH bands; degree %d of %s is reduced to its base colour\n",
                 scene.sh_degree, input_file.c_str());
  if (write == save_splat && scene.trained_kernel.kernel.compensates_opacity())
    std::fprintf(stderr,
                 "note: .splat cannot say which kernel a scene needs; %s is %s (from the %s): draw the .splat file "
                 "with --kernel %s\n",
                 input_file.c_str(), scene.trained_kernel.kernel.description().c_str(),
                 scene.trained_kernel.source.c_str(), scene.trained_kernel.kernel.spec().c_str());
  if (const std::size_t negative = write == save_ply ? count_negative_scales(scene) : 0)
    std::fprintf(stderr,
                 "note: %zu of %zu Gaussians of %s have a negative scale, which PLY's log scales cannot hold; "
                 "written as its magnitude (the same ellipsoid)\n",
                 negative, scene.size(), input_file.c_str());
  write(scene, args.output);
  std::printf("read %s (%s, %zu Gaussians, SH degree %d, decoded in %.3f s), wrote %s\n", input_file.c_str(),
              report.format.c_str(), scene.size(), scene.sh_degree, report.decode_seconds, args.output.c_str());
}

}  // namespace

void register_convert(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* sub = app.add_subcommand(
      "convert", "convert a scene (INRIA or compressed PLY, .splat, or a scene folder) to INRIA PLY or .splat");
  sub->add_option("IN", args->input, "the scene to read: any format the tool reads, or a scene folder")->required();
  sub->add_option("OUT", args->output, "the file to write; its extension picks the format: .ply or .splat")
      ->required();
  sub->add_flag("--force", args->force, "overwrite OUT if it exists");
  sub->callback([args] { run(*args); });
}

}  // namespace flashgs::cli
