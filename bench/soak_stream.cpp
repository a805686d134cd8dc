#include "soak_stream.hpp"

namespace dn::soak {

namespace {
client::ConnectOptions stream_options() {
  client::ConnectOptions o;
  o.client_name = "dn-soak";
  return o;
}
}  // namespace

Stream::Stream(const std::string& url, const protocol::PipelineInfo& pipeline, uint32_t width, uint32_t height,
               uint32_t in_flight)
    : pipeline_(pipeline.name),
      connection_(client::Connection::connect(url, stream_options())),
      frames_(session_for(pipeline, width, height, in_flight)) {
  session_.emplace(connection_.open_session(session_for(pipeline, width, height, in_flight)));
}

Stream::~Stream() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void Stream::start() { thread_ = std::thread([this] { run(); }); }

void Stream::join() {
  if (thread_.joinable()) thread_.join();
}

StreamCounts Stream::counts() const { return {submitted_.load(), done_.load(), lost_.load(), reordered_.load()}; }

std::string Stream::first_error() const {
  std::lock_guard lock(error_mutex_);
  return first_error_;
}

void Stream::note_error(const std::string& what) {
  std::lock_guard lock(error_mutex_);
  if (first_error_.empty()) first_error_ = what;
}

void Stream::account(const client::Result& r) {
  // The library already refuses a RESULT that answers another frame (a
  // Protocol error, counted below); this catches a skipped index too.
  if (r.frame_index != expected_) ++reordered_;
  expected_ = r.frame_index + 1;
  ++done_;
}

void Stream::run() {
  client::Session& s = *session_;
  uint64_t next = 0;
  // One collection step: a rejected frame is lost and the stream goes on; a
  // result for the wrong frame is a reorder; a broken connection loses every
  // frame still in flight and ends the stream.
  auto collect = [&](bool block) -> bool {
    try {
      if (block) {
        account(s.wait());
        return true;
      }
      auto r = s.poll();
      if (r) account(*r);
      return r.has_value();
    } catch (const client::Error& e) {
      note_error(e.what());
      if (e.kind() == client::ErrorKind::Protocol && e.field() == "RESULT.frame_index") {
        ++reordered_;
        return true;
      }
      if (e.kind() == client::ErrorKind::Server) {
        ++lost_;
        return true;
      }
      throw;
    }
  };
  try {
    while (!stop_) {
      // submit() waits for window space itself; results it parks come out of poll().
      s.submit(frames_.frame(next++));
      ++submitted_;
      while (collect(false)) {
      }
    }
    while (s.in_flight() > 0) collect(true);
    s.close();
  } catch (const client::Error& e) {
    // The connection is gone: what was in flight will never be answered.
    note_error(e.what());
    lost_ += s.in_flight();
  }
}

}  // namespace dn::soak
