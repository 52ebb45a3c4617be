// flashgs: render, inspect, convert, generate, benchmark and check 3D Gaussian Splatting scenes.
#include <cstdio>
#include <new>

#include "commands.h"
#include "flashgs/error.h"

int main(int argc, char** argv) {
  CLI::App app{"flashgs: a FlashGS 3D Gaussian Splatting renderer (CPU and CUDA)"};
  app.require_subcommand(1);
  // One line per error, naming the option (CLI11's default adds a "Run with --help" line).
  // Messages quote what the user typed and what files hold: control bytes are escaped.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return "error: " + flashgs::printable_message(e.what()) + "\n";
  });
  flashgs::cli::register_render(app);
  flashgs::cli::register_info(app);
  flashgs::cli::register_convert(app);
  flashgs::cli::register_generate(app);
  flashgs::cli::register_bench(app);
  flashgs::cli::register_check(app);
  flashgs::cli::register_report(app);
  flashgs::cli::register_lod(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const flashgs::Error& e) {
    std::fprintf(stderr, "error: %s\n", flashgs::printable_message(e.what()).c_str());
    return 2;
  } catch (const std::bad_alloc&) {
    // The renderers name the frame that did not fit; this is anything else that ran out.
    std::fprintf(stderr, "error: out of memory\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", flashgs::printable_message(e.what()).c_str());
    return 3;
  }
  return 0;
}
