// The process's age from /proc/self/stat (its start time in clock ticks since boot) and /proc/uptime.
#include "process_clock.h"

#include <unistd.h>

#include <fstream>
#include <sstream>
#include <string>

namespace flashgs::viewer {

double ms_since_process_start() {
  std::ifstream stat("/proc/self/stat"), uptime_file("/proc/uptime");
  std::string line;
  double uptime_s = 0;
  if (!std::getline(stat, line) || !(uptime_file >> uptime_s)) return -1;
  // The command name (field 2) may hold spaces: the fields after it start past its ')'.
  const auto close = line.rfind(')');
  if (close == std::string::npos) return -1;
  std::istringstream fields(line.substr(close + 2));
  std::string field;
  // Fields 3 onwards; the start time is field 22.
  for (int i = 3; i <= 22; ++i)
    if (!(fields >> field)) return -1;
  const long ticks = sysconf(_SC_CLK_TCK);
  if (ticks <= 0) return -1;
  return (uptime_s - std::stod(field) / double(ticks)) * 1000.0;
}

}  // namespace flashgs::viewer
