#include "server/session/service.hpp"

#include <algorithm>

#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "gpu/devices.hpp"
#include "gpu/transient_pool.hpp"
#include "server/log.hpp"

namespace dn::server {

using protocol::ErrorCode;

SessionService::SessionService(const ServerOptions& options, gpu::Context& device, std::string device_name,
                               ConnectionLayer& connections, net::EventLoop& loop, ServerCounters& counters,
                               PipelineFactory factory)
    : options_(options),
      device_(device),
      device_name_(std::move(device_name)),
      connections_(connections),
      counters_(counters),
      idle_trim_(options.idle_trim_s) {
  const uint64_t heaps = gpu::describe_device(device_.physical_device(), 0).device_local_bytes;
  device_budget_bytes_ = options_.max_device_bytes && (options_.max_device_bytes < heaps || heaps == 0)
                             ? options_.max_device_bytes
                             : heaps;
  log::info("device_memory_budget", {{"bytes", device_budget_bytes_}, {"device_local_heaps", heaps}});

  // Context-wide resources the pipelines declare (svgf-fb's F_beta table):
  // made once per device before any session can bind them, then shared
  // read-only (a second server on the same context reuses them).
  shared_resources_ = pipelines::prepare_shared_resources(device_);
  for (const auto& r : shared_resources_)
    log::info("shared_resource", {{"name", r.name}, {"ms", r.ms}, {"device", device_name_}});

  // On a worker: the frame's device work, then its replies encoded there, so the loop only queues bytes.
  scheduler_ = std::make_unique<Scheduler>(options_.workers, [this, &loop](Session& session, FrameJob& job) {
    FrameDone done = encode_replies(session.id(), session.config().output_format, job, session.run(job));
    {
      std::lock_guard lock(completions_mutex_);
      completions_.push_back(std::move(done));
    }
    loop.wake();
  });
  builder_ = std::make_unique<PipelineBuilder>(device_, [this, &loop](BuiltPipeline&& built) {
    {
      std::lock_guard lock(completions_mutex_);
      built_.push_back(std::move(built));
    }
    loop.wake();
  }, std::move(factory));
  if (options_.warm_up) {
    builder_->warm_up([this](const WarmUpReport& report) {
      {
        std::lock_guard lock(completions_mutex_);
        warm_up_ = report;
      }
      // A failure leaves some configuration a client can open cold: a warning.
      log::write(report.error.empty() ? log::Level::Info : log::Level::Warn, "warm_up",
                 {{"sessions", report.configs},
                  {"offered", report.offered},
                  {"kernels", report.kernels},
                  {"ms", report.ms},
                  {"cache_bytes", report.cache_bytes},
                  {"error", report.error}});
    });
  }
}

SessionService::~SessionService() { stop(); }

void SessionService::stop() {
  if (builder_) builder_->stop();
  if (scheduler_) scheduler_->stop();
}

void SessionService::on_request(net::Connection& c, const protocol::Header& h, protocol::Message&& message,
                                std::vector<uint8_t>&& payload) {
  std::visit(
      [&](auto&& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, protocol::OpenSession>) {
          on_open_session(c, h, m);
        } else if constexpr (std::is_same_v<T, protocol::Frame>) {
          on_frame(c, h, std::move(m), std::move(payload));
        } else if constexpr (std::is_same_v<T, protocol::Attach>) {
          on_attach(c, h, m);
        } else if constexpr (std::is_same_v<T, protocol::CloseSession>) {
          on_close_session(c, h, m);
        } else if constexpr (std::is_same_v<T, protocol::StatsRequest>) {
          on_stats(c, h);
        } else {
          error(c, h.request_id, ErrorCode::UnknownMessageType, "header.type",
                std::string(protocol::to_string(h.type)) + " is sent by servers, not clients");
        }
      },
      message);
}

bool SessionService::has_work(const net::Connection& c) const {
  if (c.sessions_being_built > 0) return true;
  return std::any_of(c.owned_sessions.begin(), c.owned_sessions.end(), [&](uint64_t sid) {
    const Session* s = sessions_.find(sid);
    return s && s->in_flight > 0;
  });
}

bool SessionService::window_full(const net::Connection& c) const {
  return std::any_of(c.owned_sessions.begin(), c.owned_sessions.end(), [&](uint64_t sid) {
    const Session* s = sessions_.find(sid);
    return s && s->in_flight >= options_.max_frames_in_flight;
  });
}

void SessionService::on_closed(net::Connection& c) {
  for (uint64_t sid : std::vector<uint64_t>(c.owned_sessions))
    if (auto s = sessions_.get(sid)) finish_session(s, false);
  for (uint64_t sid : c.watched_sessions)
    if (Session* s = sessions_.find(sid)) std::erase(s->watchers, c.id());
}

void SessionService::refresh_message_limit(net::Connection& c) {
  uint64_t largest = 0;
  for (uint64_t sid : c.owned_sessions)
    if (const Session* s = sessions_.find(sid)) largest = std::max(largest, frame_message_bytes(s->frame_config()));
  connections_.set_largest_frame(c, largest);
}

void SessionService::drain_completions() {
  std::vector<FrameDone> batch;
  std::vector<BuiltPipeline> built;
  {
    std::lock_guard lock(completions_mutex_);
    batch.swap(completions_);
    built.swap(built_);
  }
  for (BuiltPipeline& b : built) on_pipeline_built(std::move(b));
  for (FrameDone& d : batch) on_frame_done(std::move(d));
}

void SessionService::check_timers(std::chrono::steady_clock::time_point now) {
  // Scratch no frame has leased for a while goes back to the device.
  gpu::TransientPool::of(device_).trim(std::chrono::seconds(30));
  trim_when_idle(now);
}

void SessionService::trim_when_idle(std::chrono::steady_clock::time_point now) {
  bool warm_up_done = false;
  {
    std::lock_guard lock(completions_mutex_);
    warm_up_done = warm_up_.has_value();
  }
  // The warm-up's kernels stay compiled for the server's lifetime; later ones only while used.
  if (warm_up_done && !warm_up_kernels_kept_) {
    device_.kernels().keep_current();
    warm_up_kernels_kept_ = true;
  }
  const bool busy = !idle() || (options_.warm_up && !warm_up_done);
  const std::vector<uint64_t> activity{counters_.frames_processed, counters_.frames_failed, counters_.sessions_opened,
                                       counters_.connections_accepted, sessions_.size(), connections_.size()};
  if (!idle_trim_.due(activity, busy, now)) return;
  const IdleTrimReport r = trim_idle_memory(device_);
  log::info("idle_trim", {{"resident_before", r.resident_before},
                          {"resident_after", r.resident_after},
                          {"transient_bytes", r.transient_bytes},
                          {"kernels", r.kernels},
                          {"sessions", sessions_.size()},
                          {"ms", r.ms}});
}

void SessionService::on_stats(net::Connection& c, const protocol::Header& h) {
  LiveState live;
  connections_.add_live_state(live);
  live.sessions = sessions_.size();
  live.sessions_being_built = sessions_being_built_;
  live.device_budget_bytes = device_budget_bytes_;
  live.being_built_bytes = bytes_being_built_;
  live.max_sessions = options_.max_sessions;
  live.max_session_bytes = options_.max_session_bytes;
  for (auto& [id, s] : sessions_) {
    live.frames_in_flight += s->in_flight;
    live.device_bytes += s->device_bytes();  // a closed one's is freed once its last frame leaves the device
    live.transient_bytes += s->transient_bytes();
    // A session's id and figures only to its owner or an administrator: another
    // local user must not learn what to ATTACH to (docs/server.md, "Security").
    if (s->owner() != c.id() && !c.administrator) continue;
    const double pixels = static_cast<double>(uint64_t{s->config().width} * s->config().height);
    live.sessions_figures.push_back({id, s->frames_processed,
                                     static_cast<double>(s->device_bytes() - s->transient_bytes()) / pixels,
                                     static_cast<double>(s->transient_bytes()) / pixels});
  }
  {
    std::lock_guard lock(completions_mutex_);
    live.warm_up = warm_up_;
  }
  live.shared_resources = shared_resources_;
  connections_.send(c, make_stats(counters_, live, device_), h.request_id);
}

uint64_t SessionService::committed_device_bytes() const {
  uint64_t bytes = bytes_being_built_;
  for (const auto& [id, s] : sessions_) bytes += s->device_bytes();
  return bytes;
}

}  // namespace dn::server
