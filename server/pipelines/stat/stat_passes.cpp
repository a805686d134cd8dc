#include "pipelines/stat/stat_passes.hpp"

#include <cstring>
#include <vector>

#include "pipelines/stat/student_t.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

constexpr ChannelId kStatistics[] = {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3};

}  // namespace

// t^2 of the two-sided quantile t_{1 - alpha/2, nu}, entry k for nu = k + 1
// (beyond nu = 1024 within 0.2 % of the normal quantile; IMPLEMENTATION-NOTES
// A.3 4), as fp32 bytes for the Constant buffer.
std::vector<uint8_t> t_squared_table(double alpha) {
  const std::vector<float> t = student_t_table(alpha, kStatTableSize);
  std::vector<uint8_t> bytes(t.size() * sizeof(float));
  for (size_t k = 0; k < t.size(); ++k) {
    const float t2 = t[k] * t[k];
    std::memcpy(bytes.data() + k * sizeof(float), &t2, sizeof t2);
  }
  return bytes;
}

uint64_t statistics_channels() {
  uint64_t mask = 0;
  for (ChannelId id : kStatistics) mask |= protocol::channel_bit(id);
  return mask;
}

uint64_t stat_channels() {
  return protocol::channel_bit(ChannelId::Radiance) | protocol::channel_bit(ChannelId::Albedo) |
         protocol::channel_bit(ChannelId::Normal) | statistics_channels();
}

bool declares_statistics(const SessionConfig& config) {
  return (channel_mask(config) & statistics_channels()) == statistics_channels();
}

void add_stat_inputs(GraphSpec& g, const SessionConfig& config, bool with_statistics, double still_alpha) {
  g.add_input(config, ChannelId::Radiance, "radiance");
  g.add_input(config, ChannelId::Albedo, "albedo");
  g.add_input(config, ChannelId::Normal, "normal");
  if (with_statistics)
    for (ChannelId id : kStatistics) g.add_input(config, id, std::string(protocol::find_channel(id)->name));
  std::vector<uint8_t> table = t_squared_table(g.parameters.stat_alpha);
  const std::vector<uint8_t> still = t_squared_table(still_alpha);
  table.insert(table.end(), still.begin(), still.end());
  g.add_constant("stat_t_squared", std::move(table));
}

void add_stat_filter(GraphSpec& g, const SessionConfig& config, const StatSources& s) {
  const bool demodulated = g.parameters.stat_demodulated != 0.0f;
  g.add_scratch("stat_theta");
  g.add_scratch("stat_variance");
  PassSpec& prepare = g.add_pass("stat_prepare", "stat_prepare")
                          .bind("count", s.count)
                          .bind("mean", s.mean)
                          .bind("m2", s.m2)
                          .bind("m3", s.m3)
                          .bind("theta", "stat_theta")
                          .bind("variance", "stat_variance");
  prepare.pixels_per_invocation = 1;
  if (s.classify)
    prepare.bind("motion", "motion")
        .set("CLASSIFY", true);
  const bool modulates = demodulated && s.prepare_modulates;
  if (s.classify || modulates)
    prepare.bind("albedo", "albedo");
  if (demodulated) {
    // The values averaged and, for the frame's own statistics, what remodulates them.
    g.add_scratch("stat_value");
    prepare.bind("value", "stat_value")
        .bind("radiance", "radiance")
        .set("DEMODULATED", true);
    if (modulates) {
      g.add_scratch(kStatModulation);
      prepare.bind("modulation", kStatModulation).set("MODULATION", true);
    }
  }
  // The shared-memory tile measured faster on lavapipe (docs/results.md);
  // it serves radii up to its apron and writes pixel pairs within a
  // workgroup row, so the width must be even.
  const bool tiled = g.parameters.stat_radius <= static_cast<float>(kStatTileApron) && config.width % 2 == 0;
  PassSpec& filter = g.add_pass("stat_filter", tiled ? "stat_filter_tiled" : "stat_filter");
  if (tiled) filter.over_grid({config.width, config.height}, {config.width, config.height}).set("APRON", kStatTileApron);
  filter.bind("theta", "stat_theta")
      .bind("variance", "stat_variance")
      .bind("radiance", demodulated ? std::string("stat_value") : s.raw)
      .bind("albedo", "albedo")
      .bind("normal", "normal")
      .bind("t_squared", "stat_t_squared")
      .bind("result", GraphSpec::kOutput)
      .set("TABLE_SIZE", kStatTableSize)
      .set("DEMODULATED", demodulated);
  if (demodulated) filter.bind("modulation", kStatModulation);
}

// The statistics are sums that outgrow fp16 within a few hundred samples
// (docs/protocol.md §7.7): fp32 only.
std::optional<ConfigError> check_statistics(const SessionConfig& config) {
  for (size_t i = 0; i < config.channels.size(); ++i) {
    const InputChannel& c = config.channels[i];
    if (protocol::is_sample_statistic(c.id) && c.format != protocol::Format::F32)
      return ConfigError{ConfigProblem::InvalidChannel, "channels[" + std::to_string(i) + "].format",
                         config.pipeline + " takes " + std::string(protocol::find_channel(c.id)->name) +
                             " in fp32 only (the sums of squared and cubed deviations overflow fp16)"};
  }
  return std::nullopt;
}

std::optional<ConfigError> check_optional_statistics(const SessionConfig& config) {
  if (auto err = check_statistics(config)) return err;
  bool some = false;
  for (const InputChannel& c : config.channels) some = some || protocol::is_sample_statistic(c.id);
  if (some && !declares_statistics(config))
    return ConfigError{ConfigProblem::MissingChannel, "channels",
                       config.pipeline +
                           " takes all four of stat_count, stat_mean, stat_m2 and stat_m3 or none of them (without "
                           "them each frame's radiance is one sample per pixel)"};
  return std::nullopt;
}

}  // namespace dn::pipelines
