// The frame path's reasons, from the selection's technical text to the sentence the window shows.
#include "path_note.h"

namespace flashgs::viewer {
namespace {

bool starts_with(const std::string& text, const char* prefix) { return text.rfind(prefix, 0) == 0; }

}  // namespace

std::string plain_path_note(const std::string& why) {
  if (why.empty()) return why;
  if (starts_with(why, "--backend cpu")) return "CPU backend chosen (--backend cpu)";
  if (starts_with(why, "no usable CUDA device")) return "no NVIDIA GPU found: rendering on the CPU";
  if (starts_with(why, "this build has no CUDA")) return "built without CUDA: rendering on the CPU";
  if (starts_with(why, "CUDA-GL interop refused"))
    return "the GPU does not drive this display: frames go through host memory";
  if (starts_with(why, "interop failed") || starts_with(why, "CUDA path failed"))
    return "the GPU path could not start: rendering on the CPU (details in the log)";
  if (starts_with(why, "CUDA frame failed")) return "a GPU frame failed: rendering on the CPU (details in the log)";
  return why;
}

}  // namespace flashgs::viewer
