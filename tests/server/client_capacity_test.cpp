// dn::client::capacity against hand-computed expectations.
#include <gtest/gtest.h>

#include "dn/client/capacity.hpp"
#include "dn/client/error.hpp"

namespace dn::client {
namespace {

protocol::Stats figures(double busy, std::optional<double> ms_per_mp) {
  protocol::Stats s;
  s.values = {{"sessions", 3},
              {"sessions_being_built", 1},
              {"max_sessions", 16},
              {"max_session_bytes", 1e6},
              {"device_memory_free_bytes", 1'000'000},
              {"device_busy_fraction", busy},
              {"pipeline.svgf.device_bytes_fixed", 1000},
              {"pipeline.svgf.device_bytes_per_pixel", 10}};
  if (ms_per_mp) s.values.push_back({"pipeline.svgf.frame_ms_per_megapixel", *ms_per_mp});
  return s;
}

TEST(ClientCapacity, MemoryAndSessionLimit) {
  // 100 x 50: 1000 + 10 * 5000 = 51000 bytes; 1 000 000 / 51 000 = 19.6 -> 19;
  // 16 - 3 - 1 = 12 sessions left: 12 fit.
  const Capacity c = capacity(figures(0, std::nullopt), "svgf", 100, 50);
  EXPECT_EQ(c.session_bytes, 51000u);
  EXPECT_EQ(c.by_memory, 19u);
  EXPECT_EQ(c.by_session_limit, 12u);
  EXPECT_FALSE(c.frame_ms.has_value());
  EXPECT_FALSE(c.by_time.has_value());
  EXPECT_EQ(c.sessions, 12u);
}

TEST(ClientCapacity, MemoryBindsAtALargerSize) {
  // 400 x 100: 1000 + 400 000 = 401 000 bytes; 1 000 000 / 401 000 -> 2.
  EXPECT_EQ(capacity(figures(0, std::nullopt), "svgf", 400, 100).sessions, 2u);
}

TEST(ClientCapacity, FrameTimeBoundAtATargetRate) {
  // 1000 x 500 = 0.5 MP at 20 ms/MP: 10 ms a frame; at 30 fps a session takes
  // 30 * 10 / 1000 = 0.3 of the device; 1 - 0.4 busy leaves 0.6: 2 sessions
  // (0.6 / 0.3 is 1.999...98 in binary: still 2). Memory: 5 001 000 bytes > max_session_bytes.
  const Capacity c = capacity(figures(0.4, 20), "svgf", 1000, 500, 30);
  EXPECT_DOUBLE_EQ(*c.frame_ms, 10.0);
  EXPECT_EQ(*c.by_time, 2u);
  EXPECT_EQ(c.by_memory, 0u);
  EXPECT_EQ(c.sessions, 0u);

  const Capacity small = capacity(figures(0.4, 20), "svgf", 100, 50, 30);  // 0.1 ms: 0.003 each -> 200
  EXPECT_EQ(*small.by_time, 200u);
  EXPECT_EQ(small.sessions, 12u);
  const Capacity busy = capacity(figures(1.3, 20), "svgf", 100, 50, 30);  // overlapping workers: none left
  EXPECT_EQ(*busy.by_time, 0u);
  EXPECT_EQ(busy.sessions, 0u);
}

TEST(ClientCapacity, WithoutFpsTimeDoesNotBind) {
  const Capacity c = capacity(figures(0.99, 20), "svgf", 100, 50);
  EXPECT_DOUBLE_EQ(*c.frame_ms, 0.1);
  EXPECT_FALSE(c.by_time.has_value());
  EXPECT_EQ(c.sessions, 12u);
}

TEST(ClientCapacity, BadInputNamesWhatIsWrong) {
  try {
    capacity(figures(0, std::nullopt), "nope", 100, 50);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("pipeline.nope.device_bytes_fixed"), std::string::npos) << e.what();
  }
  EXPECT_THROW(capacity(figures(0, std::nullopt), "svgf", 0, 50), Error);
  EXPECT_THROW(capacity(figures(0, std::nullopt), "svgf", 10, 50, -1), Error);
  protocol::Stats old = figures(0, std::nullopt);
  old.values.erase(old.values.begin() + 4);  // a server without device_memory_free_bytes
  EXPECT_THROW(capacity(old, "svgf", 10, 10), Error);
}

}  // namespace
}  // namespace dn::client
