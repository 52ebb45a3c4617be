// Error: the one exception type for bad input; its message names the file and the problem.
#pragma once

#include <cstddef>
#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>

namespace flashgs {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Thrown by a loader that saw LoadProgress::cancel_requested: the user stopped it, nothing is wrong.
class LoadCancelled : public Error {
 public:
  explicit LoadCancelled(const std::string& path) : Error(path + ": loading cancelled") {}
};

// An exception's text for a message: "out of memory" for std::bad_alloc, whose own text says
// only "std::bad_alloc"; what() otherwise.
std::string error_text(const std::exception& e);

// Text taken from a file (a header line, a token, an img_name), made safe to put in a message:
// control bytes and invalid UTF-8 become \xNN, and text longer than `max_bytes` is cut with
// "..." and its full length, so a message stays one short line whatever the file holds.
std::string printable_file_text(std::string_view text, std::size_t max_bytes = 80);

// The most of a path that a message shows: a path is outside text too (a user's argument, a
// name read from a file), yet it must stay whole to be found.
constexpr std::size_t kMaxPrintedPathBytes = 4096;

// A message already built (it may quote paths, option values or file text) made safe for a
// terminal: control bytes and invalid UTF-8 become \xNN as printable_file_text writes them,
// while its own quotes and backslashes stay as they are.
std::string printable_message(std::string_view message);

}  // namespace flashgs
