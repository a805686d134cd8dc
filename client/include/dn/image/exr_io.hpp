// OpenEXR reading and writing for the dn tools, the benchmark and the example
// renderer. Everything is float on the way in (any pixel type is converted by
// OpenEXR), rows are top-first as stored in the file, and the data window is
// translated so that pixel (0,0) is its top-left corner.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace dn::image {

// Thrown for unreadable/unwritable files and missing channels; what() names the file.
class ImageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class ExrPixelType { Half, Float };

// Camera metadata the dnrender layout keeps in EXR header attributes.
// Matrices are the 16 floats of an Imath::M44f in memory order, which is the
// same array as a column-major GLM matrix (Imath's row-vector p' = p * M is
// GLM's column-vector p' = M * p): see docs/client.md.
struct ExrCamera {
  std::optional<std::array<float, 16>> view;        // "dn.view"        (M44f)
  std::optional<std::array<float, 16>> projection;  // "dn.projection"  (M44f)
  std::optional<std::array<float, 2>> jitter;       // "dn.jitter"      (V2f, pixels)
  std::optional<std::array<float, 16>> prev_view;        // "dn.prev_view"        (optional)
  std::optional<std::array<float, 16>> prev_projection;  // "dn.prev_projection"  (optional)
  std::optional<std::array<float, 2>> prev_jitter;       // "dn.prev_jitter"      (optional)
};

// An open EXR file (single-part scanline or tiled; part 0 of a multi-part file).
class ExrReader {
 public:
  explicit ExrReader(const std::string& path);
  ~ExrReader();
  ExrReader(ExrReader&&) noexcept;
  ExrReader& operator=(ExrReader&&) noexcept;

  const std::string& path() const { return path_; }
  int width() const { return width_; }
  int height() const { return height_; }
  const std::vector<std::string>& channels() const { return channels_; }  // sorted, as in the file
  bool has_channel(const std::string& name) const;

  // Reads the named channels, interleaved: out[(y*width + x)*names.size() + c].
  // An empty name reads as zeros. Throws ImageError naming the first missing channel.
  std::vector<float> read(const std::vector<std::string>& names) const;
  // One channel, planar.
  std::vector<float> read_channel(const std::string& name) const { return read({name}); }

  ExrCamera camera() const;
  // String attributes (for provenance in tests and tools).
  std::optional<std::string> string_attribute(const std::string& name) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  int width_ = 0, height_ = 0;
  std::vector<std::string> channels_;
};

// One output channel: `data` points at the first component of pixel (0,0),
// `stride` is the distance in floats between consecutive pixels (1 for planar,
// 3 for the R of interleaved RGB, ...). Rows are `width * stride` floats apart.
struct ExrChannelOut {
  std::string name;
  const float* data = nullptr;
  size_t stride = 1;
  ExrPixelType type = ExrPixelType::Half;
};

struct ExrWriteOptions {
  ExrCamera camera;                             // written when set
  std::map<std::string, std::string> strings;   // extra string attributes
  bool compress = true;                         // ZIP (lossless); false: none
};

void write_exr(const std::string& path, int width, int height, const std::vector<ExrChannelOut>& channels,
               const ExrWriteOptions& options = {});

// Interleaved RGB (3 floats per pixel) to channels R, G, B.
void write_exr_rgb(const std::string& path, int width, int height, const float* rgb, ExrPixelType type,
                   const ExrWriteOptions& options = {});

// Reads R,G,B (or, if absent, the first layer that has .R/.G/.B) as interleaved RGB.
std::vector<float> read_exr_rgb(const std::string& path, int& width, int& height);

}  // namespace dn::image
