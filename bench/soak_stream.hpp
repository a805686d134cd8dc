// One session of the soak: its own connection, streaming frames on a thread
// of its own until told to stop, counting what came back in order and what
// did not come back at all.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "dn/client/client.hpp"
#include "soak_frames.hpp"

namespace dn::soak {

struct StreamCounts {
  uint64_t submitted = 0;
  uint64_t done = 0;       // results received, in order
  uint64_t lost = 0;       // sent and answered with an error, or never answered
  uint64_t reordered = 0;  // a result whose frame index was not the next one expected
};

class Stream {
 public:
  // Connects and opens the session (on the calling thread).
  Stream(const std::string& url, const protocol::PipelineInfo& pipeline, uint32_t width, uint32_t height,
         uint32_t in_flight);
  ~Stream();
  void start();
  // Stops submitting; the thread then waits for the frames in flight and
  // closes the session. Ask every stream before joining any, so none streams
  // on while another drains.
  void request_stop() { stop_ = true; }
  void join();
  StreamCounts counts() const;
  const std::string& pipeline() const { return pipeline_; }
  std::string first_error() const;

 private:
  void run();
  void account(const client::Result& r);
  void note_error(const std::string& what);

  std::string pipeline_;
  client::Connection connection_;
  std::optional<client::Session> session_;
  FramePlanes frames_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> submitted_{0}, done_{0}, lost_{0}, reordered_{0};
  uint64_t expected_ = 0;
  mutable std::mutex error_mutex_;
  std::string first_error_;
  std::thread thread_;
};

}  // namespace dn::soak
