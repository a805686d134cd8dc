// Hard cases on the guides (issue 15, point 6; docs/pipelines.md "Sanitize
// rule"): for every pipeline, every non-radiance channel it takes and each
// of NaN, +-Inf, +-1e30, 3.4e38, -1 and a denormal, one frame whose plane
// holds that value in a patch (next to good pixels) among clean frames of a
// still scene, after a reset. Every output value of every frame, the bad
// one and the clean ones after it (a poisoned history shows there), must be
// finite, >= 0 and within a few times the brightest output of a session that
// never saw the bad frame; a pipeline without history must give that
// session's output exactly once the bad frame has passed. The largest
// difference from the clean session per frame is printed: svgf-family
// histories keep up to ~0.3 of the brightest value for several frames (a
// dropped or differently weighted history, not a bad value).
// The same again with every plane fp16 (statistics stay fp32, as the protocol
// requires) for the values whose half encoding differs: NaN, +Inf (what any
// value above 65504 becomes) and 65504, the largest finite half (a valid
// emitter in the emission channel, which the bound then allows for).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <ostream>
#include <memory>
#include <string>
#include <vector>

#include "gpu_test_env.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

constexpr int kW = 32, kH = 16, kN = kW * kH;
// Frames per case: clean up to kBadFrame, the bad one, then clean again.
constexpr int kFrames = 5, kBadFrame = 1;
// The patch that holds the bad value: 8x6 pixels inside the image.
bool in_patch(int x, int y) { return x >= 10 && x < 18 && y >= 5 && y < 11; }

struct BadValue {
  const char* name;
  float value;
};
const BadValue kBadValues[] = {{"NaN", std::numeric_limits<float>::quiet_NaN()},
                               {"PlusInf", std::numeric_limits<float>::infinity()},
                               {"MinusInf", -std::numeric_limits<float>::infinity()},
                               {"Plus1e30", 1e30f},
                               {"Minus1e30", -1e30f},
                               {"Max3p4e38", 3.4e38f},
                               {"MinusOne", -1.0f},
                               {"Denormal", 1e-40f}};
const BadValue kBadHalfValues[] = {{"NaN", std::numeric_limits<float>::quiet_NaN()},
                                   {"PlusInf", std::numeric_limits<float>::infinity()},
                                   {"Max65504", 65504.0f}};

// A pipeline as a session opens it: its declared channels and the ones
// tested here (every declared channel that is not the filtered light).
struct PipelineKind {
  const char* label;     // test-name part
  const char* pipeline;  // registry name
  std::vector<ChannelId> declared;
  std::vector<ChannelId> guides;
  bool stateless = false;  // no history: the frames after the bad one equal the clean session's
};

const std::vector<PipelineKind>& kinds() {
  using C = ChannelId;
  static const std::vector<PipelineKind> k = {
      {"passthrough", "passthrough", {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion},
       {C::Albedo, C::Normal, C::Depth, C::Motion}, true},
      {"accumulate", "accumulate", {C::Radiance, C::Normal, C::Depth, C::Motion}, {C::Normal, C::Depth, C::Motion}},
      {"svgf", "svgf", {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission, C::Roughness},
       {C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission, C::Roughness}},
      {"svgf_split", "svgf",
       {C::Diffuse, C::Specular, C::SpecularAlbedo, C::Albedo, C::Normal, C::Depth, C::Motion, C::Roughness},
       {C::SpecularAlbedo}},
      {"svgf_fb", "svgf-fb",
       {C::Diffuse, C::Specular, C::Albedo, C::SpecularF0, C::Roughness, C::Normal, C::Depth, C::Motion, C::Emission},
       {C::Albedo, C::SpecularF0, C::Roughness, C::Normal, C::Depth, C::Motion, C::Emission}},
      {"reflect", "reflect",
       {C::Diffuse, C::Specular, C::Emission, C::Albedo, C::SpecularF0, C::Roughness, C::Normal, C::Depth, C::Motion,
        C::Position, C::ReflectionPosition, C::ReflectionAlbedo, C::ReflectionNormal, C::ReflectionDepth,
        C::ReflectionDirection, C::ReflectionDistance, C::ReflectionFootprint},
       {C::Emission, C::Albedo, C::SpecularF0, C::Roughness, C::Normal, C::Depth, C::Motion, C::Position,
        C::ReflectionPosition, C::ReflectionAlbedo, C::ReflectionNormal, C::ReflectionDepth, C::ReflectionDirection,
        C::ReflectionDistance, C::ReflectionFootprint}},
      {"stat", "stat", {C::Radiance, C::Albedo, C::Normal, C::StatCount, C::StatMean, C::StatM2, C::StatM3},
       {C::Albedo, C::Normal, C::StatCount, C::StatMean, C::StatM2, C::StatM3}, true},
      {"stat_temporal", "stat-temporal",
       {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::StatCount, C::StatMean, C::StatM2, C::StatM3},
       {C::Albedo, C::Normal, C::Depth, C::Motion, C::StatCount, C::StatMean, C::StatM2, C::StatM3}},
      {"svgf_samples", "svgf",
       {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::Sample1Radiance, C::Sample1Normal, C::Sample1Depth,
        C::Sample1Offset},
       {C::Sample1Normal, C::Sample1Depth, C::Sample1Offset}},
      {"progressive", "progressive",
       {C::Radiance, C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission, C::SampleCount},
       {C::Albedo, C::Normal, C::Depth, C::Motion, C::Emission, C::SampleCount}},
  };
  return k;
}

// A still camera at the origin looking down -z (fovy 60 degrees), column-major.
constexpr float kTanHalf = 0.57735027f, kAspect = float(kW) / kH, kNear = 0.1f, kFar = 100.0f;
std::array<float, 16> identity() { return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; }
std::array<float, 16> projection() {
  std::array<float, 16> m{};
  m[0] = 1.0f / (kTanHalf * kAspect);
  m[5] = 1.0f / kTanHalf;
  m[10] = (kFar + kNear) / (kNear - kFar);
  m[11] = -1.0f;
  m[14] = 2.0f * kFar * kNear / (kNear - kFar);
  return m;
}

// The clean still scene: two surfaces (a plane facing the camera, a tilted
// one on the right), a background corner, smooth light, the three
// reflection classes in columns, a few emitters; statistics of 8 samples
// whose Box-Cox (lambda 1/2) mean gives the radiance back.
std::vector<float> clean_plane(ChannelId id, int x, int y) {
  // Light up to 7 (demodulated): 3.4e38 times it overflows where a guide multiplies.
  const float light = 8.0f * (0.4f + 0.3f * std::sin(0.4f * x) * std::cos(0.5f * y) + (x > 20 ? 0.2f : 0.0f));
  const bool background = x < 4 && y < 4;
  const float depth = background ? 0.0f : (x > 20 ? 3.0f + 0.05f * (x - 20) : 2.0f);
  const float nx = x > 20 ? 0.6f : 0.0f, nz = x > 20 ? 0.8f : 1.0f;
  const float px = (2.0f * (x + 0.5f) / kW - 1.0f) * kTanHalf * kAspect * depth;
  const float py = (1.0f - 2.0f * (y + 0.5f) / kH) * kTanHalf * depth;
  const float albedo[3] = {0.3f + 0.02f * (x % 8), 0.5f, 0.7f - 0.03f * (y % 6)};
  switch (id) {
    case ChannelId::Radiance:
    case ChannelId::Sample1Radiance:
    case ChannelId::Diffuse:
      return {albedo[0] * light, albedo[1] * light, albedo[2] * light};
    case ChannelId::Specular: return {0.2f * light, 0.2f * light, 0.2f * light};
    case ChannelId::Albedo: return {albedo[0], albedo[1], albedo[2]};
    case ChannelId::SpecularAlbedo: return {0.4f, 0.4f, 0.4f};
    case ChannelId::SpecularF0: return {0.04f, 0.04f, 0.04f};
    case ChannelId::Roughness: return {x % 3 == 0 ? 0.02f : x % 3 == 1 ? 0.25f : 0.8f};
    case ChannelId::Normal:
    case ChannelId::Sample1Normal: return {nx, 0.0f, nz};
    case ChannelId::Depth:
    case ChannelId::Sample1Depth: return {depth};
    case ChannelId::Sample1Offset: return {0.25f, -0.2f};
    case ChannelId::Motion: return {0.0f, 0.0f};
    case ChannelId::Emission: return (x + 3 * y) % 17 == 0 ? std::vector<float>{0.5f, 0.4f, 0.3f} : std::vector<float>(3, 0.0f);
    case ChannelId::SampleCount: return {1.0f};
    case ChannelId::Position: return {px, py, -depth};
    case ChannelId::ReflectionPosition: return {px, py + 1.0f, -depth - 1.0f};
    case ChannelId::ReflectionAlbedo: return {0.6f, 0.5f, 0.4f};
    case ChannelId::ReflectionNormal: return {0.0f, -0.6f, 0.8f};
    case ChannelId::ReflectionDepth: return {depth + 1.4f};
    case ChannelId::ReflectionDirection: return {0.0f, 0.6f, -0.8f};
    case ChannelId::ReflectionDistance: return {1.4f};
    case ChannelId::ReflectionFootprint: return {0.05f};
    case ChannelId::StatCount: return {8.0f};
    case ChannelId::StatMean: {
      std::vector<float> m;
      for (float a : albedo) m.push_back(2.0f * (std::sqrt(a * light) - 1.0f));
      return m;
    }
    case ChannelId::StatM2: return {0.02f, 0.02f, 0.02f};
    case ChannelId::StatM3: return {0.001f, 0.001f, 0.001f};
    default: throw std::logic_error("no clean plane for this channel");
  }
}

// A plane's format in a session whose planes are `planes`: statistics are fp32 only.
Format format_of(ChannelId id, Format planes) {
  const bool statistics = id == ChannelId::StatCount || id == ChannelId::StatMean || id == ChannelId::StatM2 ||
                          id == ChannelId::StatM3;
  return statistics ? Format::F32 : planes;
}

// A frame of the still scene; with `bad`, channel `bad_id` holds `bad_value`
// in every component inside the patch.
test::HostFrame frame(const PipelineKind& kind, Format planes, bool reset, bool bad, ChannelId bad_id, float bad_value) {
  test::HostFrame f;
  f.info.flags = reset ? protocol::kFrameReset : 0u;
  f.info.view = f.info.prev_view = identity();
  f.info.projection = f.info.prev_projection = projection();
  for (ChannelId id : kind.declared) {
    std::vector<float> plane;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        for (float v : clean_plane(id, x, y)) plane.push_back(bad && id == bad_id && in_patch(x, y) ? bad_value : v);
    f.add(id, format_of(id, planes), plane);
  }
  return f;
}

std::unique_ptr<pipelines::Pipeline> open(const PipelineKind& kind, Format planes) {
  std::vector<protocol::ChannelDecl> channels;
  for (ChannelId id : kind.declared) channels.push_back({id, format_of(id, planes)});
  return pipelines::create(test::context(), test::make_config(kind.pipeline, kW, kH, channels));
}

struct Case {
  size_t kind;
  ChannelId channel;
  size_t value;  // into kBadValues, or kBadHalfValues when planes are fp16
  Format planes = Format::F32;

  const BadValue& bad() const { return planes == Format::F16 ? kBadHalfValues[value] : kBadValues[value]; }
};

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (size_t k = 0; k < kinds().size(); ++k)
    for (ChannelId id : kinds()[k].guides) {
      for (size_t v = 0; v < std::size(kBadValues); ++v) cases.push_back({k, id, v});
      if (format_of(id, Format::F16) == Format::F16)
        for (size_t v = 0; v < std::size(kBadHalfValues); ++v) cases.push_back({k, id, v, Format::F16});
    }
  return cases;
}

class GuideHardCases : public test::GpuTest, public ::testing::WithParamInterface<Case> {
 protected:
  // One session per pipeline kind, reset at the start of each case (lavapipe
  // builds an svgf session in about 1.5 s, reflect in about 5 s), and its
  // clean run, made on that session first.
  struct Kind {
    std::unique_ptr<pipelines::Pipeline> session;
    std::vector<std::vector<float>> clean;
  };
  static Kind& kind_state(size_t kind, Format planes) {
    Kind& k = states()[{kind, planes}];
    if (!k.session) {
      k.session = open(kinds()[kind], planes);
      for (int t = 0; t < kFrames; ++t)
        k.clean.push_back(
            svgf_inputs::run(*k.session, frame(kinds()[kind], planes, t == 0, false, ChannelId::Radiance, 0.0f)));
    }
    return k;
  }
  static void TearDownTestSuite() { states().clear(); }

 private:
  static std::map<std::pair<size_t, Format>, Kind>& states() {
    static std::map<std::pair<size_t, Format>, Kind> s;
    return s;
  }
};

// Within this factor of the clean session's brightest output: a pixel's
// output is its filtered demodulated light (a weighted mean of neighbours'
// light over albedo, which differs by up to 0.7 / 0.3 here) times its albedo.
constexpr double kBoundFactor = 4.0;

TEST_P(GuideHardCases, OutputStaysFiniteAndBounded) {
  const Case c = GetParam();
  const PipelineKind& kind = kinds()[c.kind];
  const float bad = c.bad().value;
  Kind& state = kind_state(c.kind, c.planes);
  double brightest = 0.0;
  for (const auto& out : state.clean)
    for (float v : out) brightest = std::max(brightest, double(v));
  ASSERT_GT(brightest, 0.0);
  // A finite emission within the radiance rule's bound (65504 in fp16) is a
  // bright emitter, not a bad value: it is added back unfiltered, so the
  // output may hold it on top of the filtered light.
  const bool valid_emitter = c.channel == ChannelId::Emission && std::isfinite(bad) && bad > 0.0f && bad <= 1e12f;
  const double bound = kBoundFactor * brightest + (valid_emitter ? double(bad) : 0.0);
  std::vector<double> difference;  // largest |output - clean output| per frame
  for (int t = 0; t < kFrames; ++t) {
    const auto out = svgf_inputs::run(*state.session, frame(kind, c.planes, t == 0, t == kBadFrame, c.channel, bad));
    ASSERT_EQ(out.size(), size_t(3 * kN));
    double worst = 0.0;
    for (int i = 0; i < 3 * kN; ++i) {
      ASSERT_TRUE(std::isfinite(out[i]) && out[i] >= 0.0f && out[i] <= bound)
          << "frame " << t << " (bad frame " << kBadFrame << "), pixel (" << (i / 3) % kW << ", " << (i / 3) / kW
          << ") component " << i % 3 << ": " << out[i] << " (clean brightest " << brightest << ", bound " << bound << ")";
      worst = std::max(worst, std::fabs(double(out[i]) - state.clean[size_t(t)][size_t(i)]));
    }
    difference.push_back(worst / brightest);
    if (kind.stateless && t > kBadFrame) {
      EXPECT_EQ(worst, 0.0) << "frame " << t << " differs from the clean session's";
    }
  }
  std::printf("[ info     ] largest difference from the clean session per frame:");
  for (double d : difference) std::printf(" %.3g", d);
  std::printf("\n");
}

std::string name_of(const Case& c) {
  return std::string(kinds()[c.kind].label) + "__" + std::string(protocol::find_channel(c.channel)->name) + "__" +
         c.bad().name + (c.planes == Format::F16 ? "__fp16" : "");
}
std::string case_name(const ::testing::TestParamInfo<Case>& info) { return name_of(info.param); }
void PrintTo(const Case& c, std::ostream* os) { *os << name_of(c); }

INSTANTIATE_TEST_SUITE_P(EveryPipelineGuideAndValue, GuideHardCases, ::testing::ValuesIn(all_cases()), case_name);

}  // namespace
}  // namespace dn
