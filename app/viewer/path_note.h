// Plain-word notes for the frame path the viewer ended up on: what a user reads instead of the CUDA driver's text (which stays in the log).
#pragma once

#include <string>

namespace flashgs::viewer {

// `why` as the frame-path selection logged it ("no usable CUDA device (CUDA driver version is
// insufficient ...)", "--backend cpu", ...) in a few plain words; empty stays empty.
std::string plain_path_note(const std::string& why);

}  // namespace flashgs::viewer
