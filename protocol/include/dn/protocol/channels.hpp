// Channel identifiers, their component counts and formats: the one table of
// per-pixel data the protocol can carry. Ids are part of the wire format.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace dn::protocol {

enum class Format : uint8_t {
  F16 = 1,  // IEEE 754 binary16, little-endian
  F32 = 2,  // IEEE 754 binary32, little-endian
};

inline constexpr uint32_t bytes_per_component(Format f) { return f == Format::F16 ? 2u : 4u; }

// Conventions (normative text in docs/protocol.md):
//  - radiance channels: linear scene-referred RGB, >= 0
//  - Normal: world-space unit vector
//  - Depth: linear view depth, positive; 0 or +inf marks background
//  - Motion: pixels, see MotionConvention
enum class ChannelId : uint8_t {
  Radiance = 0,        // rgb  noisy radiance, everything (or diffuse+specular+emission)
  Diffuse = 1,         // rgb  noisy diffuse radiance (split form)
  Specular = 2,        // rgb  noisy specular radiance (split form)
  Albedo = 3,          // rgb  diffuse albedo
  SpecularF0 = 4,      // rgb  specular reflectance at normal incidence
  Roughness = 5,       // r    GGX alpha (see docs/protocol.md)
  Normal = 6,          // xyz  world-space unit normal
  Depth = 7,           // r    linear view depth
  Motion = 8,          // xy   pixels
  Emission = 9,        // rgb  emitted radiance at the primary hit (never filtered)
  Position = 10,       // xyz  world-space position of the primary hit
  SampleCount = 11,    // r    samples taken this frame (0 = none, < 1 spp rendering)
  // Lighting forms (1.2): a split signal already divided by its modulator,
  // which the session declares as a channel; the server only remodulates.
  DiffuseLighting = 12,   // rgb  diffuse radiance / albedo (Cycles DiffDir + DiffInd)
  SpecularLighting = 13,  // rgb  specular radiance / specular_albedo (Cycles GlossDir + GlossInd)
  SpecularAlbedo = 14,    // rgb  directional albedo of the specular lobes (Cycles GlossCol)
  // Reflection features (1.3; paper 001): what a reflection shows, for
  // reflection motion and the specular signal's demodulation and edges.
  ReflectionPosition = 15,   // xyz  first non-mirror hit along the mirror chain (world)
  ReflectionAlbedo = 16,     // rgb  its albedo times the chain's later mirror reflectances
  ReflectionNormal = 17,     // xyz  its world-space unit normal
  ReflectionDepth = 18,      // r    virtual depth: linear view depth of that hit unfolded onto the primary ray
  ReflectionDirection = 19,  // xyz  representative ray: the view ray mirrored about the primary normal
  ReflectionDistance = 20,   // r    distance along that ray to its first hit
  ReflectionFootprint = 21,  // r    ray-differential footprint width at that hit (world units)
  Output = 32,         // rgb  denoised radiance, only in RESULT
  // Extra samples (1.4; paper 001 §5): the channels above are sample 0, the
  // guide ray through the pixel centre; sample j = 1..3 is one more primary
  // ray of the pixel, at `offset` from the centre. Six ids per sample, in
  // this order (sample_channel() computes them).
  Sample1Radiance = 33,  // rgb  its radiance (radiance-mode sessions)
  Sample1Diffuse = 34,   // rgb  its diffuse radiance (split sessions)
  Sample1Specular = 35,  // rgb  its specular radiance (split sessions)
  Sample1Normal = 36,    // xyz  world-space unit normal of its primary hit
  Sample1Depth = 37,     // r    linear view depth of its primary hit
  Sample1Offset = 38,    // xy   its position minus the pixel centre, pixels, in [-0.5, 0.5]
  Sample2Radiance = 39, Sample2Diffuse = 40, Sample2Specular = 41, Sample2Normal = 42, Sample2Depth = 43,
  Sample2Offset = 44,
  Sample3Radiance = 45, Sample3Diffuse = 46, Sample3Specular = 47, Sample3Normal = 48, Sample3Depth = 49,
  Sample3Offset = 50,
  // Sample statistics (1.5; paper 003 Alg. 1): per RGB channel over the
  // samples the pixel took (docs/protocol.md §7.7); radiance is their raw
  // mean. fp32 only: the sums outgrow fp16 within a few hundred samples.
  StatCount = 51,  // r    samples n
  StatMean = 52,   // rgb  mean of the Box-Cox (lambda 1/2) transformed samples, 2 sqrt(x) - 2
  StatM2 = 53,     // rgb  sum of squared deviations of the transformed samples (not divided by n)
  StatM3 = 54,     // rgb  sum of cubed deviations of the transformed samples
};

// The extra-sample channels: what each of a sample's six ids carries.
enum class SampleField : uint8_t { Radiance = 0, Diffuse = 1, Specular = 2, Normal = 3, Depth = 4, Offset = 5 };
inline constexpr uint32_t kMaxExtraSamples = 3;
// The id of `field` of extra sample j (1 .. kMaxExtraSamples).
inline constexpr ChannelId sample_channel(uint32_t j, SampleField field) {
  return static_cast<ChannelId>(33u + 6u * (j - 1u) + static_cast<uint32_t>(field));
}
// What an extra-sample channel carries; nothing for every other id.
inline constexpr std::optional<SampleField> sample_field(ChannelId id) {
  const uint32_t v = static_cast<uint32_t>(id);
  if (v < 33u || v >= 33u + 6u * kMaxExtraSamples) return std::nullopt;
  return static_cast<SampleField>((v - 33u) % 6u);
}

// The sample statistics (ids 51-54, docs/protocol.md §7.7): declared all
// four or none, and in F32 only.
inline constexpr bool is_sample_statistic(ChannelId id) {
  return id == ChannelId::StatCount || id == ChannelId::StatMean || id == ChannelId::StatM2 || id == ChannelId::StatM3;
}

// Demodulated sample statistics (docs/protocol.md §7.7) divide each sample
// by the diffuse albedo of its primary hit, guarded: a component below this
// or not finite divides by 1 (the server's guard of the same name:
// shaders/include/sanitize.glsl, DN_ALBEDO_MIN).
inline constexpr float kDemodulationAlbedoMin = 1e-3f;
inline constexpr float demodulation_albedo(float a) {
  return (a >= kDemodulationAlbedoMin && a <= 3.4028234663852886e38f) ? a : 1.0f;  // NaN and +inf fail both
}

inline constexpr uint32_t kChannelIdLimit = 64;  // ids are < 64 so sets fit in a uint64 mask

struct ChannelInfo {
  ChannelId id;
  std::string_view name;
  uint32_t components;
  uint8_t since_minor = 0;  // the protocol minor version (1.x) that defines the id
};

inline constexpr ChannelInfo kChannels[] = {
    {ChannelId::Radiance, "radiance", 3},   {ChannelId::Diffuse, "diffuse", 3},
    {ChannelId::Specular, "specular", 3},   {ChannelId::Albedo, "albedo", 3},
    {ChannelId::SpecularF0, "specular_f0", 3}, {ChannelId::Roughness, "roughness", 1},
    {ChannelId::Normal, "normal", 3},       {ChannelId::Depth, "depth", 1},
    {ChannelId::Motion, "motion", 2},       {ChannelId::Emission, "emission", 3},
    {ChannelId::Position, "position", 3},   {ChannelId::SampleCount, "sample_count", 1},
    {ChannelId::DiffuseLighting, "diffuse_lighting", 3, 2}, {ChannelId::SpecularLighting, "specular_lighting", 3, 2},
    {ChannelId::SpecularAlbedo, "specular_albedo", 3, 2},
    {ChannelId::ReflectionPosition, "reflection_position", 3, 3},
    {ChannelId::ReflectionAlbedo, "reflection_albedo", 3, 3},
    {ChannelId::ReflectionNormal, "reflection_normal", 3, 3},
    {ChannelId::ReflectionDepth, "reflection_depth", 1, 3},
    {ChannelId::ReflectionDirection, "reflection_direction", 3, 3},
    {ChannelId::ReflectionDistance, "reflection_distance", 1, 3},
    {ChannelId::ReflectionFootprint, "reflection_footprint", 1, 3},
    {ChannelId::Output, "output", 3},
    {ChannelId::Sample1Radiance, "sample1_radiance", 3, 4}, {ChannelId::Sample1Diffuse, "sample1_diffuse", 3, 4},
    {ChannelId::Sample1Specular, "sample1_specular", 3, 4}, {ChannelId::Sample1Normal, "sample1_normal", 3, 4},
    {ChannelId::Sample1Depth, "sample1_depth", 1, 4},       {ChannelId::Sample1Offset, "sample1_offset", 2, 4},
    {ChannelId::Sample2Radiance, "sample2_radiance", 3, 4}, {ChannelId::Sample2Diffuse, "sample2_diffuse", 3, 4},
    {ChannelId::Sample2Specular, "sample2_specular", 3, 4}, {ChannelId::Sample2Normal, "sample2_normal", 3, 4},
    {ChannelId::Sample2Depth, "sample2_depth", 1, 4},       {ChannelId::Sample2Offset, "sample2_offset", 2, 4},
    {ChannelId::Sample3Radiance, "sample3_radiance", 3, 4}, {ChannelId::Sample3Diffuse, "sample3_diffuse", 3, 4},
    {ChannelId::Sample3Specular, "sample3_specular", 3, 4}, {ChannelId::Sample3Normal, "sample3_normal", 3, 4},
    {ChannelId::Sample3Depth, "sample3_depth", 1, 4},       {ChannelId::Sample3Offset, "sample3_offset", 2, 4},
    {ChannelId::StatCount, "stat_count", 1, 5},             {ChannelId::StatMean, "stat_mean", 3, 5},
    {ChannelId::StatM2, "stat_m2", 3, 5},                   {ChannelId::StatM3, "stat_m3", 3, 5},
};

inline constexpr const ChannelInfo* find_channel(ChannelId id) {
  for (const auto& c : kChannels)
    if (c.id == id) return &c;
  return nullptr;
}
inline constexpr const ChannelInfo* find_channel(std::string_view name) {
  for (const auto& c : kChannels)
    if (c.name == name) return &c;
  return nullptr;
}
inline constexpr uint64_t channel_bit(ChannelId id) { return uint64_t{1} << static_cast<uint32_t>(id); }

// Bytes of one plane: width * height * components * bytes per component.
inline constexpr uint64_t plane_bytes(const ChannelInfo& c, Format f, uint32_t width, uint32_t height) {
  return uint64_t{width} * height * c.components * bytes_per_component(f);
}

// The channel ids a peer of minor version `minor` knows, as a mask (bit i =
// id i; `output` is not a mask channel). After the handshake a side sends
// only ids of the negotiated minor (docs/protocol.md §10).
inline constexpr uint64_t channels_defined_in(uint8_t minor) {
  uint64_t mask = 0;
  for (const auto& c : kChannels)
    if (c.since_minor <= minor && uint32_t(c.id) < kChannelIdLimit) mask |= uint64_t(1) << uint32_t(c.id);
  return mask;
}

}  // namespace dn::protocol
