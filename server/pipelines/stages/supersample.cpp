#include "pipelines/stages/supersample.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;

using protocol::SampleField;
using protocol::sample_channel;

constexpr const char* kAssignment = "supersample_assignment";

std::string name(ChannelId id) { return std::string(protocol::find_channel(id)->name); }

// The sample field that carries `signal`'s colour.
SampleField field_of(ChannelId signal) {
  switch (signal) {
    case ChannelId::Diffuse: return SampleField::Diffuse;
    case ChannelId::Specular: return SampleField::Specular;
    default: return SampleField::Radiance;
  }
}

bool has_any_field(const SessionConfig& config, uint32_t j) {
  for (uint32_t f = 0; f < 6; ++f)
    if (has_channel(config, sample_channel(j, static_cast<SampleField>(f)))) return true;
  return false;
}

}  // namespace

uint32_t extra_samples(const SessionConfig& config) {
  uint32_t n = 0;
  while (n < protocol::kMaxExtraSamples && has_channel(config, sample_channel(n + 1, SampleField::Normal))) ++n;
  return n;
}

uint64_t extra_sample_channel_bits() {
  uint64_t bits = 0;
  for (uint32_t j = 1; j <= protocol::kMaxExtraSamples; ++j)
    for (uint32_t f = 0; f < 6; ++f) bits |= protocol::channel_bit(sample_channel(j, static_cast<SampleField>(f)));
  return bits;
}

std::optional<ConfigError> check_extra_samples(const SessionConfig& config) {
  const bool radiance = has_channel(config, ChannelId::Radiance);
  const bool lighting =
      has_channel(config, ChannelId::DiffuseLighting) || has_channel(config, ChannelId::SpecularLighting);
  bool gap = false;
  for (uint32_t j = 1; j <= protocol::kMaxExtraSamples; ++j) {
    const std::string sample = "extra sample " + std::to_string(j);
    if (!has_any_field(config, j)) {
      gap = true;
      continue;
    }
    if (gap)
      return ConfigError{ConfigProblem::MissingChannel, "channels",
                         sample + " is declared without extra sample " + std::to_string(j - 1) +
                             " (samples are numbered 1, 2, 3 without a gap)"};
    if (lighting)
      return ConfigError{ConfigProblem::InvalidChannel, "channels",
                         "extra samples carry radiance: send diffuse and specular, not the lighting forms, with them"};
    std::vector<SampleField> needed = {SampleField::Normal, SampleField::Depth, SampleField::Offset};
    if (radiance) needed.push_back(SampleField::Radiance);
    else needed.insert(needed.end(), {SampleField::Diffuse, SampleField::Specular});
    for (SampleField f : needed)
      if (!has_channel(config, sample_channel(j, f)))
        return ConfigError{ConfigProblem::MissingChannel, "channels",
                           sample + " requires channel " + name(sample_channel(j, f))};
    for (SampleField f : {SampleField::Radiance, SampleField::Diffuse, SampleField::Specular}) {
      const bool sent = radiance ? f == SampleField::Radiance : f != SampleField::Radiance;
      if (!sent && has_channel(config, sample_channel(j, f)))
        return ConfigError{ConfigProblem::InvalidChannel, "channels",
                           "channel " + name(sample_channel(j, f)) + " does not match the session's signals (" +
                               (radiance ? "radiance" : "diffuse + specular") + ")"};
    }
    for (uint32_t f = 0; f < 6 && j > 1; ++f) {
      const ChannelId id = sample_channel(j, static_cast<SampleField>(f)), first = sample_channel(1, static_cast<SampleField>(f));
      if (has_channel(config, id) && channel_format(config, id) != channel_format(config, first))
        return ConfigError{ConfigProblem::InvalidChannel, "channels",
                           "channel " + name(id) + " must have the format of " + name(first) +
                               " (the extra samples' planes of one kind share a format)"};
    }
  }
  return std::nullopt;
}

std::string mixed_signal(const std::string& input) { return "supersample_mixed_" + input; }

void add_supersample_inputs(GraphSpec& g, const SessionConfig& config, const std::vector<ChannelId>& signals) {
  for (uint32_t j = 1; j <= extra_samples(config); ++j) {
    for (ChannelId s : signals) {
      const ChannelId id = sample_channel(j, field_of(s));
      g.add_input(config, id, name(id));
    }
    for (SampleField f : {SampleField::Normal, SampleField::Depth, SampleField::Offset})
      g.add_input(config, sample_channel(j, f), name(sample_channel(j, f)));
  }
}

void add_supersample_buffers(GraphSpec& g, const std::vector<std::string>& inputs) {
  g.add_scratch(kAssignment);
  for (const std::string& input : inputs) g.add_scratch(mixed_signal(input));
}

void add_supersample_assign(GraphSpec& g, const SessionConfig& config) {
  const uint32_t n = extra_samples(config);
  PassSpec& assign = g.add_pass("supersample_assign", "supersample_assign");
  assign.bind("normal", "normal")
      .bind("depth", "depth")
      .bind("assignment", kAssignment)
      .set("SAMPLES", n);
  for (uint32_t j = 1; j <= n; ++j) {
    const std::string k = std::to_string(j);
    assign.bind("normal_" + k, name(sample_channel(j, SampleField::Normal)))
        .bind("depth_" + k, name(sample_channel(j, SampleField::Depth)))
        .bind("offset_" + k, name(sample_channel(j, SampleField::Offset)));
  }
  assign.pixels_per_invocation = 1;
}

void add_supersample_mix(GraphSpec& g, const SessionConfig& config, ChannelId signal, const std::string& input,
                         const std::string& suffix) {
  const uint32_t n = extra_samples(config);
  PassSpec& mix = g.add_pass("supersample_mix" + suffix, "supersample_mix");
  mix.bind("signal", input)
      .bind("assignment", kAssignment)
      .bind("mixed", mixed_signal(input))
      .set("SAMPLES", n);
  for (uint32_t j = 1; j <= n; ++j) mix.bind("signal_" + std::to_string(j), name(sample_channel(j, field_of(signal))));
  mix.pixels_per_invocation = 1;
}

void add_supersample_resolve(GraphSpec& g, const SessionConfig& config, const std::string& display) {
  g.add_pass("supersample_resolve", "supersample_resolve")
      .bind("src", display)
      .bind("assignment", kAssignment)
      .bind("result", GraphSpec::kOutput)
      .set("SAMPLES", extra_samples(config))
      .pixels_per_invocation = 2;
}

}  // namespace dn::pipelines
