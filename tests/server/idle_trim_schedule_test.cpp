// When the server trims idle memory (docs/server.md, "Memory an idle server
// keeps"): once per quiet period, only after the delay, never while busy.
#include <gtest/gtest.h>

#include "server/idle_trim.hpp"

namespace dn::server {
namespace {

using Clock = IdleTrimSchedule::Clock;
using std::chrono::milliseconds;

TEST(IdleTrimSchedule, OncePerQuietPeriodAfterTheDelay) {
  IdleTrimSchedule schedule(5.0);
  const Clock::time_point t0 = Clock::now();
  const std::vector<uint64_t> a{1, 2, 3};
  EXPECT_FALSE(schedule.due(a, false, t0));  // the first activity seen starts a quiet period
  EXPECT_FALSE(schedule.due(a, false, t0 + milliseconds(4900)));
  EXPECT_TRUE(schedule.due(a, false, t0 + milliseconds(5000)));
  EXPECT_FALSE(schedule.due(a, false, t0 + milliseconds(60000)));  // once per quiet period
  const std::vector<uint64_t> b{1, 2, 4};  // a frame finished: re-armed
  EXPECT_FALSE(schedule.due(b, false, t0 + milliseconds(61000)));
  EXPECT_FALSE(schedule.due(b, false, t0 + milliseconds(65900)));
  EXPECT_TRUE(schedule.due(b, false, t0 + milliseconds(66000)));
}

TEST(IdleTrimSchedule, NeverWhileBusyOrDisabled) {
  IdleTrimSchedule schedule(1.0);
  const Clock::time_point t0 = Clock::now();
  const std::vector<uint64_t> a{7};
  EXPECT_FALSE(schedule.due(a, false, t0));
  EXPECT_FALSE(schedule.due(a, true, t0 + milliseconds(2000)));   // a frame on the device
  EXPECT_FALSE(schedule.due(a, false, t0 + milliseconds(2500)));  // quiet again only from 2.0 s
  EXPECT_TRUE(schedule.due(a, false, t0 + milliseconds(3000)));

  IdleTrimSchedule off(0.0);  // --idle-trim 0
  EXPECT_FALSE(off.due(a, false, t0));
  EXPECT_FALSE(off.due(a, false, t0 + milliseconds(3600 * 1000)));
}

}  // namespace
}  // namespace dn::server
