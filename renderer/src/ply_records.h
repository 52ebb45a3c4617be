// The INRIA PLY layout written in pieces: a header for a count known up front, then the records
// of one scene after another (a scene larger than memory written as it is made).
#pragma once

#include <cstdint>
#include <string>

#include "flashgs/file_write.h"
#include "flashgs/scene.h"

namespace flashgs {

// The header of `count` Gaussians with `like`'s SH degree and trained-kernel marks.
std::string inria_ply_header(const Scene& like, std::uint64_t count);
// Appends every Gaussian of `scene` as an INRIA record (logit opacity, log scales).
void write_inria_records(const Scene& scene, OutputFile& file);

}  // namespace flashgs
