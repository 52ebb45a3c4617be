// Error: the one exception type for bad input; its message names the file and the problem.
#pragma once

#include <stdexcept>
#include <string>

namespace flashgs {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace flashgs
