// The subcommands of the `flashgs` tool; each registers itself on the CLI11 app.
#pragma once

#include <CLI/CLI.hpp>

namespace flashgs::cli {

void register_render(CLI::App& app);
void register_info(CLI::App& app);
void register_convert(CLI::App& app);
void register_generate(CLI::App& app);
void register_bench(CLI::App& app);
void register_check(CLI::App& app);
void register_report(CLI::App& app);
void register_lod(CLI::App& app);

}  // namespace flashgs::cli
