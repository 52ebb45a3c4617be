// Reading and writing the trained-kernel marks of scene files (see kernel_marks.h).
#include "kernel_marks.h"

#include <cstdlib>
#include <sstream>

#include "flashgs/error.h"

namespace flashgs {
namespace {

constexpr std::uint8_t kSpzFlagAntialiased = 0x1;
const char* const kBrushMode = "SplatRenderMode:";
const char* const kPostshotFlag = "antialiased";
const char* const kEpsilonComment = "antialias_epsilon";

// The words of a comment line.
std::vector<std::string> words_of(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

}  // namespace

TrainedKernel kernel_from_ply_comments(const std::vector<std::string>& comments) {
  TrainedKernel found;
  float epsilon = kGsplatAntialiasEpsilon;
  for (const std::string& comment : comments) {
    const std::vector<std::string> w = words_of(comment);
    if (w.size() != 2) continue;
    if (w[0] == kBrushMode && (w[1] == "mip" || w[1] == "default")) {
      found.kernel = w[1] == "mip" ? SplatKernel::antialiased() : SplatKernel::classic();
      found.source = "PLY comment \"" + printable_file_text(comment) + "\" (Brush)";
    } else if (w[0] == kPostshotFlag && (w[1] == "1" || w[1] == "0")) {
      found.kernel = w[1] == "1" ? SplatKernel::antialiased() : SplatKernel::classic();
      found.source = "PLY comment \"" + printable_file_text(comment) + "\" (Postshot)";
    } else if (w[0] == kEpsilonComment) {
      char* end = nullptr;
      const float value = std::strtof(w[1].c_str(), &end);
      if (end == w[1].c_str() + w[1].size() && value > 0.0f && value <= kMaxAntialiasEpsilon) epsilon = value;
    }
  }
  if (found.kernel.compensates_opacity()) found.kernel.epsilon = epsilon;
  return found;
}

std::vector<std::string> ply_comments_for(const TrainedKernel& kernel) {
  if (!kernel.kernel.compensates_opacity())
    return kernel.marked() ? std::vector<std::string>{std::string(kBrushMode) + " default"} : std::vector<std::string>{};
  std::vector<std::string> comments = {std::string(kBrushMode) + " mip"};
  if (kernel.kernel.epsilon != kGsplatAntialiasEpsilon) {
    std::string number = kernel.kernel.spec();
    number = number.substr(number.find('=') + 1);
    comments.push_back(std::string(kEpsilonComment) + " " + number);
  }
  return comments;
}

TrainedKernel mip_splatting_kernel() {
  return {SplatKernel::antialiased(kMipSplattingEpsilon),
          "PLY property filter_3D (Mip-Splatting; its 3D filter applied at load)"};
}

TrainedKernel kernel_from_spz_flags(std::uint8_t flags) {
  if (!(flags & kSpzFlagAntialiased)) return {};
  return {SplatKernel::antialiased(), "SPZ header flag antialiased"};
}

std::uint8_t spz_flags_for(const TrainedKernel& kernel) {
  return kernel.kernel.compensates_opacity() ? kSpzFlagAntialiased : 0;
}

bool kernel_fits_a_flag(const TrainedKernel& kernel) {
  return !kernel.kernel.compensates_opacity() || kernel.kernel.epsilon == kGsplatAntialiasEpsilon;
}

std::string sog_model_for(const TrainedKernel& kernel) {
  if (kernel.kernel.compensates_opacity()) return "antialiased";
  return kernel.marked() ? "classic" : "";
}

bool kernel_from_sog_model(const std::string& model, TrainedKernel& out) {
  if (model == "antialiased" || model == "mip") {
    out = {SplatKernel::antialiased(), "SOG meta.json \"model\": \"" + printable_file_text(model) + "\""};
  } else if (model == "default" || model == "classic") {
    out = {SplatKernel::classic(), "SOG meta.json \"model\": \"" + printable_file_text(model) + "\""};
  } else {
    return false;
  }
  return true;
}

}  // namespace flashgs
