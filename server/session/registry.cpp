#include "server/session/registry.hpp"

#include "server/session/watch_key.hpp"

namespace dn::server {

SessionRegistry::SessionRegistry() {
  std::random_device rd;
  ids_.seed((uint64_t{rd()} << 32) ^ rd());
}

std::shared_ptr<Session> SessionRegistry::add(uint64_t owner, const pipelines::PreparedPipeline& prepared,
                                              std::unique_ptr<pipelines::Pipeline> pipeline) {
  uint64_t id;
  do id = ids_(); while (id == 0 || sessions_.count(id));
  auto session = std::make_shared<Session>(id, owner, prepared, std::move(pipeline), new_watch_key());
  sessions_[id] = session;
  return session;
}

Session* SessionRegistry::find(uint64_t id) const {
  auto it = sessions_.find(id);
  return it == sessions_.end() ? nullptr : it->second.get();
}

std::shared_ptr<Session> SessionRegistry::get(uint64_t id) const {
  auto it = sessions_.find(id);
  return it == sessions_.end() ? nullptr : it->second;
}

uint64_t SessionRegistry::frames_in_flight() const {
  uint64_t n = 0;
  for (const auto& [id, s] : sessions_) n += s->in_flight;
  return n;
}

}  // namespace dn::server
