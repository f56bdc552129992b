// Reading G-code from a string in the reader tests: one file named `name`, a fresh state.
#pragma once

#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "vcut/io/gcode_reader.h"
#include "vcut/io/input_error.h"

namespace vcut::io::gcode_test {

inline kinematics::Program read_text(const std::string& text, const GcodeOptions& options, const std::string& name) {
  kinematics::Program program;
  GcodeState state;
  std::istringstream in(text);
  read_gcode(in, name, options, program, state);
  return program;
}

// The message of the InputError the text raises; fails the test when it raises none.
inline std::string error_text(const std::string& text, const GcodeOptions& options, const std::string& name) {
  try {
    read_text(text, options, name);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return {};
}

}  // namespace vcut::io::gcode_test
