// stat: the statistical (Welch t-test) denoiser of paper 003 (Sakai et al.
// 2024; docs/pipelines.md "stat"): stat_prepare turns each pixel's sample
// statistics into a skew-corrected Box-Cox mean and the variance of that
// mean, stat_filter averages the raw means of the neighbours in a disc whose
// means the Welch test cannot tell apart from the pixel's.
#include <cstring>
#include <string>

#include "pipelines/definitions.hpp"
#include "pipelines/student_t.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

// Per pixel, fp32: vec4(theta rgb, n) and vec4(variance of the mean rgb, 0).
constexpr uint64_t kThetaBytes = 16;
constexpr uint64_t kVarianceBytes = 16;
// Entries of the critical-value table: nu = 1 .. 1024 (beyond, within 0.2 %
// of the normal quantile; IMPLEMENTATION-NOTES A.3 4).
constexpr int kTableSize = 1024;

constexpr ChannelId kStatistics[] = {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3};

// t^2 of the two-sided quantile t_{1 - alpha/2, nu}, entry k for nu = k + 1,
// as fp32 bytes for the Constant buffer.
std::vector<uint8_t> t_squared_table(double alpha) {
  const std::vector<float> t = student_t_table(alpha, kTableSize);
  std::vector<uint8_t> bytes(t.size() * sizeof(float));
  for (size_t k = 0; k < t.size(); ++k) {
    const float t2 = t[k] * t[k];
    std::memcpy(bytes.data() + k * sizeof(float), &t2, sizeof t2);
  }
  return bytes;
}

// The statistics are sums that outgrow fp16 within a few hundred samples
// (docs/protocol.md §7.7): fp32 only.
std::optional<ConfigError> check_statistics(const SessionConfig& config) {
  for (size_t i = 0; i < config.channels.size(); ++i) {
    const protocol::ChannelDecl& c = config.channels[i];
    if (protocol::is_sample_statistic(c.id) && c.format != protocol::Format::F32)
      return ConfigError{protocol::ErrorCode::InvalidChannel, "OPEN_SESSION.channels[" + std::to_string(i) + "].format",
                         "stat takes " + std::string(protocol::find_channel(c.id)->name) +
                             " in fp32 only (the sums of squared and cubed deviations overflow fp16)"};
  }
  return std::nullopt;
}

GraphSpec build(const SessionConfig& config) {
  GraphSpec g = begin_graph(config);
  g.add_input(config, ChannelId::Radiance, "radiance");
  g.add_input(config, ChannelId::Albedo, "albedo");
  g.add_input(config, ChannelId::Normal, "normal");
  g.add_input(config, ChannelId::StatCount, "stat_count");
  g.add_input(config, ChannelId::StatMean, "stat_mean");
  g.add_input(config, ChannelId::StatM2, "stat_m2");
  g.add_input(config, ChannelId::StatM3, "stat_m3");
  g.add_constant("stat_t_squared", t_squared_table(g.parameters.stat_alpha));
  g.add_scratch("stat_theta", kThetaBytes);
  g.add_scratch("stat_variance", kVarianceBytes);
  g.add_output(config);

  g.add_pass("stat_prepare", "stat_prepare")
      .bind("count", "stat_count")
      .bind("mean", "stat_mean")
      .bind("m2", "stat_m2")
      .bind("m3", "stat_m3")
      .bind("theta", "stat_theta")
      .bind("variance", "stat_variance")
      .pixels_per_invocation = 1;
  g.add_pass("stat_filter", "stat_filter")
      .bind("theta", "stat_theta")
      .bind("variance", "stat_variance")
      .bind("radiance", "radiance")
      .bind("albedo", "albedo")
      .bind("normal", "normal")
      .bind("t_squared", "stat_t_squared")
      .bind("result", "output")
      .set("RADIANCE_HALF", is_half(channel_format(config, ChannelId::Radiance)))
      .set("ALBEDO_HALF", is_half(channel_format(config, ChannelId::Albedo)))
      .set("NORMAL_HALF", is_half(channel_format(config, ChannelId::Normal)))
      .set("OUTPUT_HALF", is_half(config.output_format))
      .set("TABLE_SIZE", static_cast<uint32_t>(kTableSize));
  return g;
}

}  // namespace

PipelineDefinition stat_definition() {
  PipelineDefinition d;
  d.description.name = "stat";
  d.description.summary =
      "Statistical denoiser (paper 003): the raw means of the neighbours in a disc whose Box-Cox means a Welch t-test "
      "cannot tell apart from the pixel's, weighted by distance, albedo and normal.";
  d.description.required_channels = protocol::channel_bit(ChannelId::Radiance) |
                                    protocol::channel_bit(ChannelId::Albedo) |
                                    protocol::channel_bit(ChannelId::Normal);
  for (ChannelId id : kStatistics) d.description.required_channels |= protocol::channel_bit(id);
  d.parameter_groups = {"stat"};
  d.description.parameters = parameters_of(d.parameter_groups);
  d.build = build;
  d.check_channels = check_statistics;
  return d;
}

}  // namespace dn::pipelines
