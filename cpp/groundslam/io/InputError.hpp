#pragma once
#include <stdexcept>
#include <string>

namespace groundslam {

/// Bad user input (a file, a line, a key): the message names where, and the CLI exits non-zero.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace groundslam
