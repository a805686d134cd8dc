// dn denoise --fail: an idiff-like pass/fail verdict on the error against the
// -r reference. A frame fails when its metric (relMSE by default, or RMSE) is
// above the threshold; the run fails when more than --fail-percent of the
// measured frames fail, and dn exits with kExitThresholdExceeded.
#pragma once

#include <cstddef>
#include <string>

namespace dn::cli {

enum class FailMetric { RelMse, Rmse };

// "relmse" or "rmse"; UsageError naming --fail-metric otherwise.
FailMetric parse_fail_metric(const std::string& name);
const char* to_string(FailMetric metric);

struct FailThreshold {
  FailMetric metric = FailMetric::RelMse;
  double limit = 0;            // a frame fails when its metric is above this
  double allowed_percent = 0;  // of the measured frames that may fail
};

class ThresholdCheck {
 public:
  explicit ThresholdCheck(FailThreshold threshold) : threshold_(threshold) {}

  void add(long long frame, double rmse, double relmse);
  bool failed() const;
  // "PASS: ..." or "FAILURE: ...": how many frames were above the limit and the worst one.
  std::string verdict() const;

 private:
  FailThreshold threshold_;
  size_t frames_ = 0, over_ = 0;
  double worst_ = -1;
  long long worst_frame_ = -1;
};

}  // namespace dn::cli
