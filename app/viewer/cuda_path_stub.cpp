// The CUDA frame path of a build without the CUDA backend: always declines, so the CPU path is used.
#include "frame_path.h"

namespace flashgs::viewer {

std::unique_ptr<FramePath> make_cuda_path(ImagePresenter*, std::string* why) {
  *why = "this build has no CUDA backend";
  return nullptr;
}

}  // namespace flashgs::viewer
