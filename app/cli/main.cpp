// flashgs: render, inspect, generate, benchmark and check 3D Gaussian Splatting scenes.
#include <cstdio>

#include "commands.h"
#include "flashgs/error.h"

int main(int argc, char** argv) {
  CLI::App app{"flashgs: a FlashGS 3D Gaussian Splatting renderer (CPU and CUDA)"};
  app.require_subcommand(1);
  flashgs::cli::register_render(app);
  flashgs::cli::register_info(app);
  flashgs::cli::register_generate(app);
  flashgs::cli::register_bench(app);
  flashgs::cli::register_check(app);
  flashgs::cli::register_report(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const flashgs::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 3;
  }
  return 0;
}
