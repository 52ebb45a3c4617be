// `flashgs report`: (being written)
#include "commands.h"
namespace flashgs::cli {
void register_report(CLI::App& app) { (void)app; }
}  // namespace flashgs::cli
