#include "stream.hpp"

#include <cstdio>
#include <filesystem>
#include <optional>
#include <stdexcept>

#include "dn/client/client.hpp"
#include "dn/client/parameters.hpp"
#include "dn/client/watch_file.hpp"
#include "dn/image/exr_io.hpp"
#include "frame_exr.hpp"

namespace dn::render {

using protocol::ChannelId;

const std::vector<float>* stream_plane(const FrameBuffers& fb, ChannelId id) {
  switch (id) {
    case ChannelId::Radiance: return &fb.radiance;
    case ChannelId::Diffuse: return &fb.diffuse;
    case ChannelId::Specular: return &fb.specular;
    case ChannelId::Albedo: return &fb.albedo;
    case ChannelId::SpecularF0: return &fb.specular_f0;
    case ChannelId::Roughness: return &fb.roughness;
    case ChannelId::Normal: return &fb.normal;
    case ChannelId::Depth: return &fb.depth;
    case ChannelId::Motion: return &fb.motion;
    case ChannelId::Emission: return &fb.emission;
    case ChannelId::Position: return &fb.position;
    case ChannelId::SampleCount: return &fb.sample_count;
    case ChannelId::ReflectionPosition: return &fb.reflection_position;
    case ChannelId::ReflectionAlbedo: return &fb.reflection_albedo;
    case ChannelId::ReflectionNormal: return &fb.reflection_normal;
    case ChannelId::ReflectionDepth: return &fb.reflection_depth;
    case ChannelId::ReflectionDirection: return &fb.reflection_direction;
    case ChannelId::ReflectionDistance: return &fb.reflection_distance;
    case ChannelId::ReflectionFootprint: return &fb.reflection_footprint;
    case ChannelId::StatCount: return &fb.stat_count;
    case ChannelId::StatMean: return &fb.stat_mean;
    case ChannelId::StatM2: return &fb.stat_m2;
    case ChannelId::StatM3: return &fb.stat_m3;
    default: break;
  }
  for (uint32_t j = 1; j <= fb.extra.size(); ++j) {
    const FrameBuffers::ExtraSample& e = fb.extra[j - 1];
    using protocol::SampleField;
    if (id == protocol::sample_channel(j, SampleField::Radiance)) return &e.radiance;
    if (id == protocol::sample_channel(j, SampleField::Diffuse)) return &e.diffuse;
    if (id == protocol::sample_channel(j, SampleField::Specular)) return &e.specular;
    if (id == protocol::sample_channel(j, SampleField::Normal)) return &e.normal;
    if (id == protocol::sample_channel(j, SampleField::Depth)) return &e.depth;
    if (id == protocol::sample_channel(j, SampleField::Offset)) return &e.offset;
  }
  return nullptr;
}

ChannelSet channels_for(uint64_t takes, bool send_split) {
  auto takes_any = [&](std::initializer_list<ChannelId> ids) {
    for (ChannelId id : ids)
      if (takes & protocol::channel_bit(id)) return true;
    return false;
  };
  ChannelSet set;
  const bool split = takes_any({ChannelId::Diffuse}) && takes_any({ChannelId::Specular}) &&
                     (send_split || !takes_any({ChannelId::Radiance}));
  set.split = split || takes_any({ChannelId::Emission});  // emission comes with the split
  set.gbuffer = takes_any({ChannelId::Albedo, ChannelId::SpecularF0, ChannelId::Roughness, ChannelId::Normal,
                           ChannelId::Depth, ChannelId::Position});
  set.motion = takes_any({ChannelId::Motion});
  set.sample_count = takes_any({ChannelId::SampleCount});
  set.reflection = takes_any({ChannelId::ReflectionPosition, ChannelId::ReflectionAlbedo, ChannelId::ReflectionNormal,
                              ChannelId::ReflectionDepth, ChannelId::ReflectionDirection,
                              ChannelId::ReflectionDistance, ChannelId::ReflectionFootprint});
  set.statistics = takes_any({ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3});
  return set;
}

std::vector<ChannelId> stream_channels(uint64_t takes, const FrameBuffers& sample, bool send_split) {
  auto has = [&](ChannelId id) {
    const auto* p = stream_plane(sample, id);
    return p && !p->empty();
  };
  auto bit = [](ChannelId id) { return protocol::channel_bit(id); };
  const bool split = has(ChannelId::Diffuse) && has(ChannelId::Specular) && (takes & bit(ChannelId::Diffuse)) &&
                     (takes & bit(ChannelId::Specular)) && (send_split || !(takes & bit(ChannelId::Radiance)));
  // The sample statistics go all four or none (docs/protocol.md §7.7).
  bool statistics = true;
  for (ChannelId id : {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3})
    statistics = statistics && (takes & bit(id)) && has(id);
  std::vector<ChannelId> ids;
  for (const auto& c : protocol::kChannels) {
    if (c.id == ChannelId::Output || !(takes & bit(c.id)) || !has(c.id)) continue;
    if (split && c.id == ChannelId::Radiance) continue;
    if (!split && (c.id == ChannelId::Diffuse || c.id == ChannelId::Specular)) continue;
    if (protocol::is_sample_statistic(c.id) && !statistics) continue;
    if (const auto field = protocol::sample_field(c.id)) {
      // Extra samples carry the colour the session's signals are sent in.
      using protocol::SampleField;
      if (*field == SampleField::Radiance && split) continue;
      if ((*field == SampleField::Diffuse || *field == SampleField::Specular) && !split) continue;
    }
    ids.push_back(c.id);
  }
  return ids;
}

struct FrameStreamer::State {
  client::ConnectOptions connect;
  std::optional<client::Connection> connection;  // until the session opens and takes it over
  protocol::PipelineInfo pipeline;
  std::optional<client::ReconnectingSession> session;
  std::vector<ChannelId> channels;
};

namespace {

client::ConnectOptions connect_options() {
  client::ConnectOptions o;
  o.client_name = "dnrender";
  return o;
}

// The one line a reconnection prints: the stream goes on, its history does not.
void print_reconnected(const client::Reconnected& r) {
  std::fprintf(stderr,
               "dnrender: reconnected to %s after losing session %llu (%s): %llu frame%s in flight lost; new session "
               "%llu from frame %llu, history reset (%u attempt%s, %.1f s)\n",
               r.endpoint.c_str(), static_cast<unsigned long long>(r.old_session_id), r.cause.c_str(),
               static_cast<unsigned long long>(r.frames_lost), r.frames_lost == 1 ? "" : "s",
               static_cast<unsigned long long>(r.new_session_id), static_cast<unsigned long long>(r.first_frame_index),
               r.attempts, r.attempts == 1 ? "" : "s", static_cast<double>(r.took.count()) / 1e3);
}

// The session's id and ready `dn watch` / `dn preview` commands: when the
// session opens and again when a reconnection replaces it (new id, new watch
// key), which is also written to the watch key file for its watchers.
void announce_session(client::Session& session, const std::string& watch_key_file, bool quiet) {
  if (!watch_key_file.empty()) client::write_watch_file(watch_key_file, {session.watch_key(), session.id()});
  if (!quiet) std::fputs(client::owner_hints("dnrender", session, watch_key_file).c_str(), stderr);
}

}  // namespace

FrameStreamer::FrameStreamer(const StreamOptions& options) : options_(options) {
  state_ = std::make_unique<State>();
  state_->connect = connect_options();
  state_->connection.emplace(client::Connection::connect(options.url, state_->connect));
  const client::Connection* connection = &*state_->connection;
  const protocol::PipelineInfo* info = connection->find_pipeline(options.pipeline);
  if (!info) {
    std::string names;
    for (const auto& p : connection->welcome().pipelines) names += (names.empty() ? "" : ", ") + p.name;
    throw std::runtime_error("server " + connection->endpoint() + " has no pipeline '" + options.pipeline +
                             "' (it offers: " + names + ")");
  }
  state_->pipeline = *info;
}

ChannelSet FrameStreamer::channels_needed() const {
  return channels_for(state_->pipeline.required_channels | state_->pipeline.optional_channels, options_.send_split);
}

void FrameStreamer::open(const FrameBuffers& sample) {
  const StreamOptions& options = options_;
  const protocol::PipelineInfo* info = &state_->pipeline;
  const uint64_t takes = info->required_channels | info->optional_channels;
  auto has = [&](ChannelId id) {
    const auto* p = stream_plane(sample, id);
    return p && !p->empty();
  };
  client::SessionDesc desc;
  desc.width = static_cast<uint32_t>(sample.width);
  desc.height = static_cast<uint32_t>(sample.height);
  desc.pipeline = options.pipeline;
  desc.max_in_flight = static_cast<uint32_t>(options.in_flight);
  desc.share_input = options.share_input;
  // Every plane is sent as fp32 (the sample statistics must be: docs/protocol.md §7.7).
  for (ChannelId id : stream_channels(takes, sample, options.send_split)) {
    desc.channel(id, protocol::Format::F32);
    state_->channels.push_back(id);
    channel_names_.emplace_back(protocol::find_channel(id)->name);
  }
  for (const auto& c : protocol::kChannels)
    if ((info->required_channels & protocol::channel_bit(c.id)) && !has(c.id))
      throw std::runtime_error("pipeline " + options.pipeline + " requires channel " + std::string(c.name) +
                               ", which this render does not produce");
  if (options.statistics_demodulated && has(ChannelId::StatCount) && (takes & protocol::channel_bit(ChannelId::StatCount))) {
    const client::DemodulatedStatistics how = client::demodulated_statistics(*info);
    if (how == client::DemodulatedStatistics::Unsupported)
      throw std::runtime_error("pipeline " + options.pipeline +
                               " has no parameter 'demodulated': it cannot take demodulated statistics "
                               "(render them with --stats instead of --stats-demodulated)");
    if (how == client::DemodulatedStatistics::ByParameter)
      desc.parameters.push_back({std::string(client::kDemodulatedParameter), 1.0});
  }
  // A lost server connection costs the frames in flight and the history, not
  // the run: the session reconnects and reopens (docs/client.md, "Reconnecting
  // after a lost server").
  client::ReconnectOptions reconnect;
  reconnect.give_up_after = std::chrono::milliseconds(static_cast<int64_t>(options.reconnect_for_s * 1e3));
  reconnect.on_reconnect = [state = state_.get(), quiet = options.quiet,
                            key_file = options.watch_key_file](const client::Reconnected& r) {
    print_reconnected(r);
    // Called once the new session is open: session() is it.
    if (state->session && state->session->session()) announce_session(*state->session->session(), key_file, quiet);
  };
  client::Connection connection = std::move(*state_->connection);
  state_->connection.reset();
  state_->session.emplace(std::move(connection), desc, state_->connect, reconnect);
  announce_session(*state_->session->session(), options.watch_key_file, options.quiet);
  if (!options.out_dir.empty()) std::filesystem::create_directories(options.out_dir);
}

FrameStreamer::~FrameStreamer() = default;

void FrameStreamer::submit(int frame, const FrameBuffers& fb, const Camera& camera, const Camera& previous,
                           bool reset) {
  client::FrameInput in;
  in.frame_index = static_cast<uint64_t>(frame);
  in.fill_previous_camera = false;
  in.info.view = to_array(camera.view);
  in.info.projection = to_array(camera.projection);
  in.info.jitter = {camera.jitter.x, camera.jitter.y};
  in.info.prev_view = to_array(previous.view);
  in.info.prev_projection = to_array(previous.projection);
  in.info.prev_jitter = {previous.jitter.x, previous.jitter.y};
  in.no_output = options_.out_dir.empty();
  if (reset) in.reset();
  if (!state_->session) open(fb);
  for (ChannelId id : state_->channels) in.add(id, std::span<const float>(*stream_plane(fb, id)));
  state_->session->submit(in);
  write_ready(false);
}

void FrameStreamer::write_ready(bool block) {
  client::ReconnectingSession& s = *state_->session;
  while (s.in_flight() > 0) {
    std::optional<client::Result> r;
    try {
      r = block ? std::optional<client::Result>(s.wait()) : s.poll();
    } catch (const client::Error& e) {
      // A frame lost with the connection: said, and the stream goes on (the
      // next submit reconnects). Any other error ends the run.
      if (e.kind() != client::ErrorKind::Transport) throw;
      std::fprintf(stderr, "dnrender: %s\n", e.what());
      continue;
    }
    if (!r) return;
    if (!options_.quiet)
      std::fprintf(stderr, "dnrender: denoised frame %llu  e2e %.1f ms  server %.1f ms\n",
                   static_cast<unsigned long long>(r->frame_index), r->latency.count(), r->total_timing_ms());
    if (!options_.out_dir.empty() && r->has_output()) {
      char name[64];
      std::snprintf(name, sizeof name, "denoised_%04llu.exr", static_cast<unsigned long long>(r->frame_index));
      const std::vector<float> rgb = r->rgb();
      image::write_exr_rgb((std::filesystem::path(options_.out_dir) / name).string(), static_cast<int>(r->width),
                           static_cast<int>(r->height), rgb.data(), image::ExrPixelType::Half);
    }
  }
}

void FrameStreamer::finish() {
  if (!state_->session) return;
  write_ready(true);
  state_->session->close();
}

}  // namespace dn::render
