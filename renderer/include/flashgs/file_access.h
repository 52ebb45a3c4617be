// Checking and reading the files a user names, and checking the files a user asks to have
// written, so that a folder, FIFO, device, symbolic-link loop or oversized file gets one clear
// message and nothing ever blocks.
#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

namespace flashgs {

struct LoadProgress;

// What a path names once symbolic links are followed.
enum class PathKind { regular_file, folder, other };

// Throws flashgs::Error "<path>: cannot open: ..." for a missing path, a dangling link, a
// link loop or a path that may not be searched; otherwise says what the path names.
PathKind path_kind(const std::string& path);

// Throws flashgs::Error "<path>: ..." unless `path` names a regular file (after links):
// folders, FIFOs, devices and sockets are refused without being opened.
void check_regular_file(const std::string& path);

// Throws flashgs::Error "<path>: ..." unless `path` may be written as an output file: a
// regular file (after links) that may be written, or nothing yet, in a folder that exists and
// may be written. Folders, FIFOs (opening one blocks until a reader comes), devices (a link to
// /dev/full or /dev/null too), sockets, dangling links and link loops are refused without
// being opened.
void check_output_file(const std::string& path);

// The whole content of the regular file at `path`, checked as above and opened without
// blocking; throws flashgs::Error when it holds more than `max_bytes`. With `progress`, the
// file is read in chunks of a few MB: bytes_total and bytes_done follow, and a set
// cancel_requested throws flashgs::LoadCancelled before the next chunk.
std::vector<char> read_regular_file(const std::string& path,
                                    std::size_t max_bytes = std::numeric_limits<std::size_t>::max(),
                                    LoadProgress* progress = nullptr);

// The first `max_bytes` of the regular file at `path` (all of it when shorter), checked and
// opened as above: what a format recogniser looks at before the whole file is read.
std::vector<char> read_file_start(const std::string& path, std::size_t max_bytes);

}  // namespace flashgs
