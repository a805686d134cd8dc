// The open sessions of a server, by id: random 64-bit ids (never 0, never
// reused while open; not secret: the watch key is), lookup and removal.
// Touched only by the event loop.
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <unordered_map>

#include "server/session/session.hpp"

namespace dn::server {

class SessionRegistry {
 public:
  SessionRegistry();

  // Registers a new session of `owner` (a connection id) under a fresh id and watch key.
  std::shared_ptr<Session> add(uint64_t owner, const pipelines::PreparedPipeline& prepared,
                               std::unique_ptr<pipelines::Pipeline> pipeline);
  // nullptr when no such session is open.
  Session* find(uint64_t id) const;
  std::shared_ptr<Session> get(uint64_t id) const;
  void erase(uint64_t id) { sessions_.erase(id); }
  size_t size() const { return sessions_.size(); }

  // Frames queued or on the device over every session.
  uint64_t frames_in_flight() const;

  auto begin() const { return sessions_.begin(); }
  auto end() const { return sessions_.end(); }

 private:
  std::unordered_map<uint64_t, std::shared_ptr<Session>> sessions_;
  std::mt19937_64 ids_;
};

}  // namespace dn::server
