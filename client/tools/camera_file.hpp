// The --camera FILE format of dn denoise: one line per frame,
//
//   # comment (also after the numbers)
//   frame <n> view <16 floats> projection <16 floats> [jitter <x> <y>]
//
// matrices column-major in the protocol's convention (docs/protocol.md §5.6.1:
// view world -> view, OpenGL, camera down -z; projection view -> clip,
// unjittered), jitter in pixels. examples/blender/export_camera.py writes it.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace dn::cli {

// A malformed camera file; what() is "FILE:LINE: what was expected, what was found".
class CameraFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct FileCamera {
  std::array<float, 16> view{};
  std::array<float, 16> projection{};
  std::optional<std::array<float, 2>> jitter;
};

// Frame number -> camera. `name` is used in error messages.
std::map<long long, FileCamera> parse_camera_text(const std::string& text, const std::string& name = "camera file");
std::map<long long, FileCamera> read_camera_file(const std::string& path);

}  // namespace dn::cli
