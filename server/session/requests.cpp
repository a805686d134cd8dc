// The session service's requests: OPEN_SESSION (validated here, built off the
// loop by the PipelineBuilder), FRAME, ATTACH, CLOSE_SESSION, and the fan-out
// of each finished frame to the owner and its watchers.
#include <algorithm>

#include "server/log.hpp"
#include "server/session/service.hpp"
#include "server/session/watch_key.hpp"
#include "server/session/wire_config.hpp"

namespace dn::server {

using protocol::ErrorCode;

namespace {

// What this watcher's RESULT copies carry: the noisy radiance where the
// owner shares it and the watcher's protocol knows the second plane (1.7),
// the sample counts where it knows them (1.9).
ResultForm watcher_form(const Session& s, const net::Connection& watcher) {
  return {s.share_input && watcher.negotiated_minor >= protocol::kShareInputMinor,
          watcher.negotiated_minor >= protocol::kSamplesMinor};
}

}  // namespace

void SessionService::on_open_session(net::Connection& c, const protocol::Header& h, const protocol::OpenSession& m) {
  if (shutting_down_) return error(c, h.request_id, ErrorCode::ShuttingDown, "", "server is shutting down");
  if (m.width > options_.max_width || m.height > options_.max_height)
    return error(c, h.request_id, ErrorCode::LimitExceeded, m.width > options_.max_width ? "OPEN_SESSION.width" : "OPEN_SESSION.height",
                      "resolution " + std::to_string(m.width) + "x" + std::to_string(m.height) + " exceeds the server's " +
                          std::to_string(options_.max_width) + "x" + std::to_string(options_.max_height));
  if (sessions_.size() + sessions_being_built_ >= options_.max_sessions)
    return error(c, h.request_id, ErrorCode::LimitExceeded, "sessions",
                      "server already has " + std::to_string(sessions_.size() + sessions_being_built_) +
                          " sessions (--max-sessions " +
                          std::to_string(options_.max_sessions) + ")");

  // Channel ids this connection's version does not define (docs/protocol.md §10).
  for (size_t i = 0; i < m.channels.size(); ++i)
    if (const auto* info = protocol::find_channel(m.channels[i].id); info && info->since_minor > c.negotiated_minor)
      return error(c, h.request_id, ErrorCode::InvalidChannel, "OPEN_SESSION.channels[" + std::to_string(i) + "]",
                        "channel '" + std::string(info->name) + "' (id " + std::to_string(int(info->id)) +
                            ") is defined from protocol 1." + std::to_string(int(info->since_minor)) +
                            "; this connection speaks 1." + std::to_string(int(c.negotiated_minor)));

  const bool share_input = (h.flags & protocol::kFlagShareInput) != 0;
  if (share_input && c.negotiated_minor < protocol::kShareInputMinor)
    return error(c, h.request_id, ErrorCode::ReservedFlags, "header.flags",
                      "flag SHARE_INPUT is defined from protocol 1." + std::to_string(int(protocol::kShareInputMinor)) +
                          "; this connection speaks 1." + std::to_string(int(c.negotiated_minor)));
  if (share_input && std::none_of(m.channels.begin(), m.channels.end(), [](const protocol::ChannelDecl& d) {
        return d.id == protocol::ChannelId::Radiance;
      }))
    return error(c, h.request_id, ErrorCode::MissingChannel, "OPEN_SESSION.channels",
                      "flag SHARE_INPUT shares the 'radiance' plane with watchers, and this session declares none");

  // Validation builds the pass graph (pure data, no device work); the builder reuses it.
  auto prepared = pipelines::prepare(session_config(m));
  if (auto* err = std::get_if<pipelines::ConfigError>(&prepared))
    return error(c, h.request_id, error_code(err->problem), open_session_field(err->field), err->message);
  const pipelines::PreparedPipeline& ready = std::get<pipelines::PreparedPipeline>(prepared);

  // A frame of this session (every channel declared) must fit one message.
  const uint64_t frame_bytes = frame_message_bytes(ready.frame_config());
  if (frame_bytes > options_.max_message_bytes)
    return error(c, h.request_id, ErrorCode::LimitExceeded, "OPEN_SESSION.channels",
                      "a frame of this session needs " + std::to_string(frame_bytes) + " bytes, above the " +
                          std::to_string(options_.max_message_bytes) + "-byte message limit (--max-message)");
  const uint64_t estimate = ready.device_bytes();
  if (estimate > options_.max_session_bytes)
    return error(c, h.request_id, ErrorCode::LimitExceeded, "OPEN_SESSION.width",
                      "session needs " + std::to_string(estimate) + " bytes of device memory, above the " +
                          std::to_string(options_.max_session_bytes) + "-byte limit (--max-session-memory)");
  // All sessions together stay within the device budget (docs/server.md "Capacity").
  if (const uint64_t committed = committed_device_bytes(); committed + estimate > device_budget_bytes_)
    return error(c, h.request_id, ErrorCode::LimitExceeded, "OPEN_SESSION.width",
                      "session needs " + std::to_string(estimate) + " bytes of device memory; " +
                          std::to_string(device_budget_bytes_ - std::min(committed, device_budget_bytes_)) +
                          " of the server's " + std::to_string(device_budget_bytes_) +
                          "-byte budget are free (--max-device-memory)");

  // Compiling and allocating happen on the builder thread: this loop goes on serving other connections.
  ++c.sessions_being_built;
  ++sessions_being_built_;
  bytes_being_built_ += estimate;
  builder_->submit(BuildRequest{c.id(), h.request_id, ready, share_input});
}

void SessionService::on_pipeline_built(BuiltPipeline&& built) {
  --sessions_being_built_;
  bytes_being_built_ -= built.request.prepared.device_bytes();
  counters_.add_build(built);
  net::Connection* c = connections_.find(built.request.connection_id);
  if (c) --c->sessions_being_built;
  const pipelines::SessionConfig& config = built.request.prepared.config();
  const uint64_t request_id = built.request.request_id;
  if (!c) {
    log::info("session.dropped", {{"conn", built.request.connection_id}, {"reason", "connection closed while building"}});
    return;  // the pipeline (and its device memory) goes with `built`
  }
  if (!built.pipeline) {
    log::error("session.create_failed", {{"conn", c->id()}, {"pipeline", config.pipeline}, {"reason", built.error}});
    error(*c, request_id, ErrorCode::DeviceError, "OPEN_SESSION",
               "could not create the pipeline on the device: " + built.error);
    return connections_.update_interest(*c);
  }
  if (shutting_down_) {
    error(*c, request_id, ErrorCode::ShuttingDown, "", "server is shutting down");
    return connections_.update_interest(*c);
  }

  std::shared_ptr<Session> session;
  try {
    session = sessions_.add(c->id(), built.request.prepared, std::move(built.pipeline));
  } catch (const std::runtime_error& e) {  // no randomness for the watch key: refuse rather than guessable
    log::error("session.create_failed", {{"conn", c->id()}, {"reason", e.what()}});
    error(*c, request_id, ErrorCode::Internal, "OPEN_SESSION", std::string("cannot draw a watch key: ") + e.what());
    return connections_.update_interest(*c);
  }
  session->share_input = built.request.share_input;
  const uint64_t id = session->id();
  c->owned_sessions.push_back(id);
  refresh_message_limit(*c);  // before the next header is read: this session's frames may follow at once
  ++counters_.sessions_opened;
  log::info("session.open", {{"conn", c->id()},
                             {"session", id},
                             {"pipeline", config.pipeline},
                             {"choice", session->choice_reason()},
                             {"width", config.width},
                             {"height", config.height},
                             {"device_bytes", session->device_bytes()},
                             {"build_ms", built.build_ms},
                             {"compile_ms", built.compile_ms}});
  protocol::Session reply{id, config.width, config.height, config.pipeline, config.output_format,
                         session->device_bytes(), false, channel_decls(session->frame_config())};
  // A 1.5 client cannot carry the key: its session can be watched by no one.
  if (c->negotiated_minor >= protocol::kWatchKeyMinor) reply.watch_key = session->watch_key();
  if (c->negotiated_minor >= protocol::kWatchUrlMinor) reply.watch_url = options_.advertise_url;
  if (c->negotiated_minor >= protocol::kAutoMinor) reply.pipeline_reason = session->choice_reason();
  connections_.send(*c, reply, request_id);
  connections_.update_interest(*c);
}

void SessionService::on_frame(net::Connection& c, const protocol::Header& h, protocol::Frame&& m, std::vector<uint8_t>&& payload) {
  const std::shared_ptr<Session> s = sessions_.get(m.info.session_id);
  if (!s || s->owner() != c.id())
    return error(c, h.request_id, ErrorCode::UnknownSession, "FRAME.session_id",
                      "session " + std::to_string(m.info.session_id) + " is not open on this connection");
  if (s->closing)
    return error(c, h.request_id, ErrorCode::UnknownSession, "FRAME.session_id",
                      "session " + std::to_string(s->id()) + " is closing");
  if (shutting_down_)
    return error(c, h.request_id, ErrorCode::ShuttingDown, "", "server is shutting down");
  auto checked = s->check_frame(m);
  if (auto* err = std::get_if<protocol::Error>(&checked)) return error(c, h.request_id, err->code, err->field, err->message);

  s->last_frame_index = m.info.frame_index;
  ++s->in_flight;
  FrameJob job;
  job.request_id = h.request_id;
  job.owner_wants_output = (h.flags & protocol::kFlagNoOutput) == 0;
  job.owner_gets_samples = c.negotiated_minor >= protocol::kSamplesMinor;
  for (uint64_t w : s->watchers)
    if (const net::Connection* wc = connections_.find(w)) job.watcher_forms[watcher_form(*s, *wc).index()] = true;
  job.frame = std::move(m);
  job.input = std::get<pipelines::FrameInput>(std::move(checked));
  job.payload = std::move(payload);  // the planes view into this buffer; moving a vector keeps its storage
  scheduler_->submit(s, std::move(job));
  if (s->in_flight >= options_.max_frames_in_flight) c.set_reading_paused(true);  // backpressure: stop reading
}

void SessionService::on_attach(net::Connection& c, const protocol::Header& h, const protocol::Attach& m) {
  if (c.negotiated_minor < protocol::kWatchKeyMinor || !m.watch_key)
    return error(c, h.request_id, ErrorCode::UnknownSession, "ATTACH.watch_key",
                      "ATTACH needs the session's watch key, which protocol 1." +
                          std::to_string(int(protocol::kWatchKeyMinor)) + " adds; this connection speaks 1." +
                          std::to_string(int(c.negotiated_minor)) + " (upgrade the client)");
  Session* found = sessions_.find(m.session_id);
  // Compare against a stand-in key when there is no session, so the time taken
  // does not tell the two refusals apart either.
  static const std::string kNoSessionKey(protocol::kWatchKeyLength, '-');
  const bool key_ok = watch_key_matches(found ? found->watch_key() : kNoSessionKey, *m.watch_key);
  // One refusal whether the id is unknown or the key wrong, so an id alone
  // (guessed, or seen in a log) says nothing about what runs here.
  if (!found || !key_ok || found->closing)
    return error(c, h.request_id, ErrorCode::UnknownSession, "ATTACH.session_id",
                      "no open session " + std::to_string(m.session_id) + " with that watch key");
  Session& s = *found;
  if (std::find(s.watchers.begin(), s.watchers.end(), c.id()) == s.watchers.end()) s.watchers.push_back(c.id());
  if (std::find(c.watched_sessions.begin(), c.watched_sessions.end(), s.id()) == c.watched_sessions.end())
    c.watched_sessions.push_back(s.id());
  const auto& cfg = s.config();
  log::info("session.attach", {{"conn", c.id()}, {"session", s.id()}});
  // The watcher already holds the key; the reply does not repeat it.
  protocol::Session reply{s.id(), cfg.width, cfg.height, cfg.pipeline, cfg.output_format, s.device_bytes(), true,
                          channel_decls(s.frame_config())};
  reply.watch_key = std::string();
  if (c.negotiated_minor >= protocol::kWatchUrlMinor) reply.watch_url = options_.advertise_url;
  if (c.negotiated_minor >= protocol::kAutoMinor) reply.pipeline_reason = s.choice_reason();
  connections_.send(c, reply, h.request_id);
}

void SessionService::on_close_session(net::Connection& c, const protocol::Header& h, const protocol::CloseSession& m) {
  std::shared_ptr<Session> s = sessions_.get(m.session_id);
  if (!s || s->owner() != c.id() || s->closing)
    return error(c, h.request_id, ErrorCode::UnknownSession, "CLOSE_SESSION.session_id",
                      "session " + std::to_string(m.session_id) + " is not open on this connection");
  s->closing = true;
  s->close_request_id = h.request_id;
  if (s->in_flight == 0) finish_session(s, true);  // else finished when its last frame completes
}

void SessionService::finish_session(const std::shared_ptr<Session>& s, bool notify) {
  scheduler_->cancel(*s);
  protocol::SessionClosed closed{s->id(), s->frames_processed};
  if (notify) {
    if (net::Connection* owner = connections_.find(s->owner())) connections_.send(*owner, closed, s->close_request_id);
  }
  for (uint64_t w : s->watchers) {
    if (net::Connection* wc = connections_.find(w)) {
      connections_.send(*wc, closed, 0);
      std::erase(wc->watched_sessions, s->id());
      connections_.update_interest(*wc);
    }
  }
  if (net::Connection* owner = connections_.find(s->owner())) {
    std::erase(owner->owned_sessions, s->id());
    refresh_message_limit(*owner);
    connections_.update_interest(*owner);
  }
  log::info("session.close", {{"session", s->id()}, {"frames", s->frames_processed}});
  sessions_.erase(s->id());  // device memory is freed when the last worker reference goes
}

void SessionService::on_frame_done(FrameDone&& done) {
  const std::shared_ptr<Session> found = sessions_.get(done.session_id);
  if (!found) return;  // session closed by a disconnect: nobody to deliver to
  const std::shared_ptr<Session>& s = found;
  if (s->in_flight > 0) --s->in_flight;
  if (done.failed) {
    ++counters_.frames_failed;
    log::error("frame.failed", {{"session", s->id()}, {"frame", done.frame_index}});
  } else {
    ++counters_.frames_processed;
    ++s->frames_processed;
    counters_.add_frame_timings(done.timings);
    counters_.frame_times.add(s->config().pipeline, uint64_t{s->config().width} * s->config().height, done.timings);
  }
  if (net::Connection* owner = connections_.find(s->owner())) {
    connections_.send_encoded(*owner, done.owner_message);
    connections_.update_interest(*owner);
  }
  for (uint64_t w : s->watchers) {
    net::Connection* wc = connections_.find(w);
    if (!wc) continue;
    // A watcher that attached after the frame was submitted has no copy encoded for it: it gets the next frame.
    const auto& message = done.watcher_messages[watcher_form(*s, *wc).index()];
    if (!message) continue;
    connections_.send_watched(*wc, message, s->id());
  }
  if (s->closing && s->in_flight == 0) finish_session(s, true);
}

}  // namespace dn::server
