// Reads the two-line TSV `dn denoise --summary FILE` writes, for end-to-end tests.
#pragma once

#include <fstream>
#include <map>
#include <sstream>
#include <string>

namespace dn::test {

// Every column of a `dn denoise --summary` file by its header name.
inline std::map<std::string, double> summary_columns(const std::string& path) {
  std::ifstream in(path);
  std::string header, values;
  std::getline(in, header);
  std::getline(in, values);
  std::stringstream h(header), v(values);
  std::map<std::string, double> columns;
  std::string name, value;
  while (std::getline(h, name, '\t') && std::getline(v, value, '\t')) columns[name] = std::stod(value);
  return columns;
}

}  // namespace dn::test
