#include "reference_threshold.hpp"

#include <cstdio>

#include "args.hpp"

namespace dn::cli {

FailMetric parse_fail_metric(const std::string& name) {
  if (name == "relmse") return FailMetric::RelMse;
  if (name == "rmse") return FailMetric::Rmse;
  throw UsageError("--fail-metric: expected relmse or rmse, got '" + name + "'");
}

const char* to_string(FailMetric metric) { return metric == FailMetric::RelMse ? "relmse" : "rmse"; }

void ThresholdCheck::add(long long frame, double rmse, double relmse) {
  const double value = threshold_.metric == FailMetric::RelMse ? relmse : rmse;
  ++frames_;
  // NaN compares false everywhere: count it as over the limit, not as within.
  if (!(value <= threshold_.limit)) ++over_;
  if (!(value <= worst_)) {
    worst_ = value;
    worst_frame_ = frame;
  }
}

bool ThresholdCheck::failed() const {
  return frames_ > 0 && 100.0 * double(over_) / double(frames_) > threshold_.allowed_percent;
}

std::string ThresholdCheck::verdict() const {
  char buf[256];
  const char* metric = to_string(threshold_.metric);
  if (frames_ == 0) return "PASS: no frame measured against the reference";
  std::snprintf(buf, sizeof buf,
                "%s: %zu of %zu frames (%.3g %%) have %s above %g, %g %% allowed; worst %s %.6g (frame %lld)",
                failed() ? "FAILURE" : "PASS", over_, frames_, 100.0 * double(over_) / double(frames_), metric,
                threshold_.limit, threshold_.allowed_percent, metric, worst_, worst_frame_);
  return buf;
}

}  // namespace dn::cli
