#include "camera_file.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

namespace dn::cli {

namespace {

std::vector<std::string> split_words(const std::string& line) {
  std::vector<std::string> words;
  std::istringstream in(line);
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

}  // namespace

std::map<long long, FileCamera> parse_camera_text(const std::string& text, const std::string& name) {
  std::map<long long, FileCamera> cameras;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto where = [&] { return name + ":" + std::to_string(line_no) + ": "; };
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.erase(hash);
    const std::vector<std::string> w = split_words(line);
    if (w.empty()) continue;
    size_t i = 0;
    auto number = [&](const std::string& what) -> double {
      if (i >= w.size()) throw CameraFileError(where() + "expected " + what + ", found the end of the line");
      const std::string& s = w[i];
      char* end = nullptr;
      errno = 0;
      const double v = std::strtod(s.c_str(), &end);
      if (end == s.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(v))
        throw CameraFileError(where() + "expected " + what + " (a finite number), found '" + s + "'");
      ++i;
      return v;
    };
    auto keyword = [&](const char* kw) {
      if (i >= w.size() || w[i] != kw)
        throw CameraFileError(where() + "expected '" + kw + "', found " +
                              (i < w.size() ? "'" + w[i] + "'" : std::string("the end of the line")) +
                              " (format: frame N view <16 floats> projection <16 floats> [jitter X Y])");
      ++i;
    };
    auto matrix = [&](const char* kw, std::array<float, 16>& m) {
      keyword(kw);
      for (int k = 0; k < 16; ++k) {
        if (i >= w.size() || (w[i].size() > 0 && std::isalpha(static_cast<unsigned char>(w[i][0])) &&
                              w[i] != "inf" && w[i] != "nan"))
          throw CameraFileError(where() + "expected 16 numbers after '" + kw + "' (column-major), found " +
                                std::to_string(k));
        m[size_t(k)] = float(number(std::string(kw) + "[" + std::to_string(k) + "]"));
      }
    };
    keyword("frame");
    const double n = number("a frame number");
    if (n != std::floor(n) || n < 0 || n > 9.0e15)
      throw CameraFileError(where() + "expected a frame number (an integer >= 0), found '" + w[1] + "'");
    const long long frame = (long long)n;
    FileCamera cam;
    matrix("view", cam.view);
    matrix("projection", cam.projection);
    if (i < w.size()) {
      keyword("jitter");
      const float jx = float(number("jitter x (pixels)"));
      const float jy = float(number("jitter y (pixels)"));
      cam.jitter = std::array<float, 2>{jx, jy};
    }
    if (i < w.size()) throw CameraFileError(where() + "unexpected '" + w[i] + "' after the camera");
    if (cameras.count(frame))
      throw CameraFileError(where() + "frame " + std::to_string(frame) + " is given twice");
    cameras.emplace(frame, cam);
  }
  if (cameras.empty()) throw CameraFileError(name + ": no 'frame N view ... projection ...' lines");
  return cameras;
}

std::map<long long, FileCamera> read_camera_file(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw CameraFileError("cannot read camera file " + path);
  std::ostringstream text;
  text << f.rdbuf();
  return parse_camera_text(text.str(), path);
}

}  // namespace dn::cli
