#include "well_behaved.hpp"

#include <cstring>
#include <deque>

#include "raw_client.hpp"

namespace dn::test {

WellBehavedClient::WellBehavedClient(std::string url, int frames, int in_flight)
    : url_(std::move(url)), frames_(frames), in_flight_(in_flight) {
  thread_ = std::thread([this] { run(); });
}

WellBehavedClient::~WellBehavedClient() {
  if (thread_.joinable()) thread_.join();
}

std::string WellBehavedClient::join() {
  if (thread_.joinable()) thread_.join();
  return failure_;
}

void WellBehavedClient::run() {
  try {
    constexpr uint32_t w = 64, h = 32;
    RawClient client(url_);
    client.hello();
    auto request = passthrough_session(w, h);
    uint64_t sid = client.open(request);
    std::deque<int> outstanding;
    int next = 0;
    while (received_ < frames_) {
      while (next < frames_ && static_cast<int>(outstanding.size()) < in_flight_) {
        auto f = make_frame(sid, static_cast<uint64_t>(next), w, h, request.channels, static_cast<float>(next));
        client.send(f.frame, 1000 + static_cast<uint64_t>(next));
        outstanding.push_back(next++);
      }
      auto r = client.receive(60.0);
      if (!r) throw std::runtime_error("no result for frame " + std::to_string(outstanding.front()));
      auto* result = std::get_if<protocol::Result>(&r->message);
      if (!result) throw std::runtime_error("expected RESULT, got " + std::string(protocol::to_string(r->header.type)));
      const int expected = outstanding.front();
      outstanding.pop_front();
      if (result->frame_index != static_cast<uint64_t>(expected) || r->header.request_id != 1000u + expected)
        throw std::runtime_error("result for frame " + std::to_string(result->frame_index) + " arrived, expected " +
                                 std::to_string(expected));
      if (result->planes.size() != 1 || result->planes[0].bytes.size() != size_t{w} * h * 3 * 4)
        throw std::runtime_error("result of frame " + std::to_string(expected) + " has a wrong output plane");
      float first, last;
      std::memcpy(&first, result->planes[0].bytes.data(), 4);
      std::memcpy(&last, result->planes[0].bytes.data() + result->planes[0].bytes.size() - 4, 4);
      if (first != static_cast<float>(expected) || last != static_cast<float>(expected))
        throw std::runtime_error("frame " + std::to_string(expected) + " came back with another frame's pixels");
      ++received_;
    }
  } catch (const std::exception& e) {
    failure_ = e.what();
  }
}

}  // namespace dn::test
