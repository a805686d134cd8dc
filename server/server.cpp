#include "server/server.hpp"

#include <signal.h>
#include <sys/epoll.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "gpu/context.hpp"
#include "gpu/pipeline_cache.hpp"
#include "server/log.hpp"

namespace dn::server {
namespace {

using Clock = std::chrono::steady_clock;

constexpr int kTimerTickMs = 200;

}  // namespace

Server::Server(ServerOptions options, gpu::Context& device, std::string device_name, PipelineFactory factory)
    : options_(std::move(options)),
      device_(device),
      device_name_(std::move(device_name)),
      connections_(options_, loop_, counters_, device_name_),
      service_(options_, device_, device_name_, connections_, loop_, counters_, std::move(factory)) {
  connections_.set_handler(&service_);
  loop_.set_wake_handler([this] { service_.drain_completions(); });
}

Server::~Server() {
  service_.stop();
  if (signal_fd_ >= 0) ::close(signal_fd_);
}

void Server::request_stop() {
  stop_requested_ = true;
  loop_.wake();
}

void Server::run(bool handle_signals) {
  if (handle_signals) {
    sigset_t mask;
    sigemptyset(&mask);
    sigaddset(&mask, SIGTERM);
    sigaddset(&mask, SIGINT);
    pthread_sigmask(SIG_BLOCK, &mask, nullptr);
    signal_fd_ = ::signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    if (signal_fd_ < 0) throw std::runtime_error(std::string("signalfd: ") + std::strerror(errno));
    loop_.add(signal_fd_, EPOLLIN, [this](uint32_t) {
      signalfd_siginfo info;
      while (::read(signal_fd_, &info, sizeof info) == sizeof info) {
        log::info("signal", {{"signal", info.ssi_signo == SIGTERM ? "SIGTERM" : "SIGINT"}});
        stop_requested_ = true;
      }
    });
  }
  log::info("ready", {{"device", device_name_}, {"workers", options_.workers}});
  for (;;) {
    run_once(kTimerTickMs);
    if (shutting_down_ && shutdown_complete()) break;
  }
  connections_.close_all("shutdown");
  service_.stop();
  save_pipeline_cache();
  log::info("stopped", {{"frames", counters_.frames_processed}});
}

void Server::run_once(int timeout_ms) {
  loop_.run_once(timeout_ms);
  if (stop_requested_ && !shutting_down_) begin_shutdown();
  const auto now = Clock::now();
  connections_.check_timers(now);
  service_.check_timers(now);
}

void Server::begin_shutdown() {
  shutting_down_ = true;
  shutdown_deadline_ = Clock::now() + std::chrono::milliseconds(static_cast<int64_t>(options_.shutdown_grace_s * 1000));
  connections_.begin_shutdown();
  service_.begin_shutdown();
  log::info("shutdown.begin", {{"frames_in_flight", service_.frames_in_flight()}, {"connections", connections_.size()}});
}

bool Server::shutdown_complete() const {
  if (Clock::now() >= shutdown_deadline_) {
    log::warn("shutdown.deadline", {{"grace_s", options_.shutdown_grace_s}});
    return true;
  }
  return quiescent();
}

void Server::save_pipeline_cache() {
  try {
    const uint64_t bytes = device_.pipeline_cache().save();
    if (bytes) log::info("pipeline_cache.saved", {{"path", device_.pipeline_cache().path()}, {"bytes", bytes}});
  } catch (const std::exception& e) {
    log::warn("pipeline_cache.save_failed", {{"reason", e.what()}});
  }
}

}  // namespace dn::server
