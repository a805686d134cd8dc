// A whole text file as a string, for the tests that read a doc or a source file.
#pragma once

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace dn::test {

// The file's contents; std::runtime_error naming it when it cannot be opened.
inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace dn::test
