// A well-behaved renderer running in the background during misbehaviour
// tests: it streams frames through a passthrough session and checks that
// every result arrives, in order, with its own frame's contents.
#pragma once

#include <atomic>
#include <string>
#include <thread>

namespace dn::test {

class WellBehavedClient {
 public:
  WellBehavedClient(std::string url, int frames, int in_flight = 2);
  ~WellBehavedClient();
  // Waits for the run to end; returns an empty string on success, else what went wrong.
  std::string join();
  int results_received() const { return received_; }

 private:
  void run();
  std::string url_;
  int frames_;
  int in_flight_;
  std::atomic<int> received_{0};
  std::string failure_;
  std::thread thread_;
};

}  // namespace dn::test
