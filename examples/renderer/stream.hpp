// Streams rendered frames through a dnserver session, pipelined: submit()
// sends a frame and returns, so the next frame renders while the server
// denoises this one; results are collected as they arrive and written to
// <out>/denoised_%04d.exr.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "camera.hpp"
#include "render.hpp"

namespace dn::render {

struct StreamOptions {
  std::string url;        // tcp://HOST:PORT or unix:///path
  std::string pipeline;   // server pipeline name (svgf, svgf-fb, ...)
  int in_flight = 2;      // frames kept in flight
  bool send_split = false;  // send diffuse + specular instead of radiance when the pipeline takes both
  std::string out_dir;    // empty: results are received but not written
  bool quiet = false;
};

class FrameStreamer {
 public:
  // Connects and opens the session; the channels sent are the pipeline's
  // required and optional ones that `sample` (a rendered frame) has.
  FrameStreamer(const StreamOptions& options, const FrameBuffers& sample);
  ~FrameStreamer();
  void submit(int frame, const FrameBuffers& fb, const Camera& camera, const Camera& previous, bool reset);
  void finish();  // waits for every outstanding result
  const std::vector<std::string>& channel_names() const { return channel_names_; }

 private:
  void write_ready(bool block);
  struct State;
  std::unique_ptr<State> state_;
  StreamOptions options_;
  std::vector<std::string> channel_names_;
};

}  // namespace dn::render
