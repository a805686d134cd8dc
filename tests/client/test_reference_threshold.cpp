// dn denoise --fail / --fail-metric / --fail-percent (client/tools/reference_threshold.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "args.hpp"
#include "reference_threshold.hpp"

namespace {

using namespace dn::cli;

TEST(ReferenceThreshold, AFrameAboveTheLimitFailsTheRun) {
  ThresholdCheck check({FailMetric::RelMse, 0.01, 0.0});
  check.add(1, 5.0, 0.005);
  EXPECT_FALSE(check.failed());
  EXPECT_EQ(check.verdict().rfind("PASS: 0 of 1 frames", 0), 0u) << check.verdict();
  check.add(2, 0.1, 0.02);
  EXPECT_TRUE(check.failed());
  EXPECT_EQ(check.verdict(),
            "FAILURE: 1 of 2 frames (50 %) have relmse above 0.01, 0 % allowed; worst relmse 0.02 (frame 2)");
}

TEST(ReferenceThreshold, MetricAndAllowedPercent) {
  ThresholdCheck rmse({FailMetric::Rmse, 0.5, 25.0});
  for (int f = 0; f < 4; ++f) rmse.add(f, f == 3 ? 0.6 : 0.1, 100.0);  // relmse ignored
  EXPECT_FALSE(rmse.failed()) << rmse.verdict();  // 25 % over, 25 % allowed
  rmse.add(4, 0.7, 0.0);
  EXPECT_TRUE(rmse.failed()) << rmse.verdict();  // 40 %
  ThresholdCheck nan({FailMetric::RelMse, 1.0, 0.0});
  nan.add(0, NAN, NAN);
  EXPECT_TRUE(nan.failed()) << "a NaN error is not within any limit";
  EXPECT_EQ(parse_fail_metric("rmse"), FailMetric::Rmse);
  EXPECT_THROW(parse_fail_metric("ssim"), UsageError);
}

}  // namespace
