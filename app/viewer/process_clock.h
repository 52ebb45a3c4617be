// How long ago this process started (exec), as the kernel counts it: start-up figures include the dynamic linking and static initialisation that run before main().
#pragma once

namespace flashgs::viewer {

// Milliseconds since the process started (resolution: the kernel's clock tick, 10 ms on
// Linux); -1 where /proc does not say.
double ms_since_process_start();

}  // namespace flashgs::viewer
