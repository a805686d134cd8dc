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
#include "dn/protocol/channels.hpp"
#include "render.hpp"

namespace dn::render {

struct StreamOptions {
  std::string url;        // tcp://HOST:PORT or unix:///path
  std::string pipeline;   // server pipeline name (svgf, svgf-fb, ...)
  int in_flight = 2;      // frames kept in flight
  bool send_split = false;  // send diffuse + specular instead of radiance when the pipeline takes both
  bool share_input = false;  // SessionDesc::share_input: watchers also get the noisy radiance
  std::string watch_key_file;  // rewritten with each session's watch key and id (client::write_watch_file)
  std::string out_dir;    // empty: results are received but not written
  // The frames' sample statistics are demodulated (dnrender --stats-demodulated):
  // the session is opened with the pipeline's parameter demodulated = 1.
  bool statistics_demodulated = false;
  bool quiet = false;
  // After a lost connection, how long to keep trying to reconnect (dnrender --reconnect-for).
  double reconnect_for_s = 30.0;
};

// What to render for a pipeline that takes the channel mask `takes`
// (required | optional): split lighting and emission only when they will be
// sent, G-buffers, motion, the reflection features (ids 15-21) and the sample
// statistics (ids 51-54) only when the pipeline reads some of them.
ChannelSet channels_for(uint64_t takes, bool send_split);

// The plane of `fb` that channel `id` is streamed from (nullptr: none; empty:
// not rendered). The sample statistics are fb.stat_count/_mean/_m2/_m3.
const std::vector<float>* stream_plane(const FrameBuffers& fb, protocol::ChannelId id);

// The channels a session declares for a pipeline taking `takes`, given a
// rendered frame: the taken ones the frame has, radiance or the split
// (send_split), the extra samples' colour in the session's form, and the
// sample statistics only all four together. In protocol order; each is
// streamed as fp32.
std::vector<protocol::ChannelId> stream_channels(uint64_t takes, const FrameBuffers& sample, bool send_split);

class FrameStreamer {
 public:
  // Connects and looks the pipeline up; the session opens with the first
  // frame, declaring the pipeline's required and optional channels that the
  // frame has.
  explicit FrameStreamer(const StreamOptions& options);
  ~FrameStreamer();
  // The channels worth rendering for this pipeline (channels_for).
  ChannelSet channels_needed() const;
  void submit(int frame, const FrameBuffers& fb, const Camera& camera, const Camera& previous, bool reset);
  void finish();  // waits for every outstanding result
  const std::vector<std::string>& channel_names() const { return channel_names_; }  // after the first submit()

 private:
  void open(const FrameBuffers& sample);  // the session, with the channels `sample` has
  void write_ready(bool block);
  struct State;
  std::unique_ptr<State> state_;
  StreamOptions options_;
  std::vector<std::string> channel_names_;
};

}  // namespace dn::render
