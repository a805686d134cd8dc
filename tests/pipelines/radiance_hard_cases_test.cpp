// Hard cases on the light (docs/pipelines.md, "Sanitize rule" and "Output
// format conversion"): for every pipeline, every light channel it filters
// and both output formats, one frame whose light holds an extreme value in a
// patch (3.4e38, FLT_MAX, 1e11, 1e12, -1e38, a denormal, or a mix of these
// with NaN, +-Inf and clean values) among clean frames of the still scene of
// guide_hard_cases_test.cpp, after a reset. Checked for every frame, the bad
// one and the clean ones after it (where a poisoned history shows):
//  - every output value is finite and >= 0, and at most 65504 in fp16
//    (saturated, never Inf); passthrough, which does not sanitize, returns
//    its finite input converted exactly (fp16: saturated) and 0 for NaN, +-Inf;
//  - the output equals, bit for bit, that of a session given the same
//    frames with the sanitize rule applied on the host (NaN, +-Inf,
//    negatives and values above 1e12 are black samples): the device sees
//    nothing else of the bad values. The svgf family's still running mean
//    leaves a sample the sanitizer changed out instead (converge_still,
//    docs/pipelines.md), so it is off here; the guide suite runs it;
//  - what is left of a bright valid sample v (1e11, 1e12) decays as a
//    running mean forgets it: after the reset frame the bad frame is the 2nd
//    sample of the history, so at frame t its weight is at most 1 / (t + 1);
//    spatial filters take normalised weighted means, so |output - clean
//    session's output| <= kBoundFactor * (brightest + v / (t + 1)) with
//    kBoundFactor covering remodulation by a neighbour's larger albedo (as
//    in the guide suite). An overflowing or non-finite history fails this.
//  - a pipeline without history gives the clean session's output exactly
//    once the bad frame has passed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "gpu_test_env.hpp"
#include "hard_case_scene.hpp"
#include "pipelines/pipeline.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;
using namespace hard_cases;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kFltMax = std::numeric_limits<float>::max();
// The radiance bound of the sanitize rule (DN_MAX_RADIANCE, shaders/include/sanitize.glsl).
constexpr float kMaxRadiance = 1e12f;
constexpr double kHalfMax = 65504.0;
constexpr double kBoundFactor = 4.0;

// The mixed patch cycles through these, component by component; kClean
// keeps the clean value there.
constexpr float kClean = -123.0f;
const float kMixed[] = {kNaN, 3.4e38f, kInf, 1e11f, -kInf, kFltMax, kClean, -1e38f, 1e12f, 1e-40f, 2e12f};

struct LightValue {
  const char* name;
  float value;  // kClean: the mixed patch
};
const LightValue kLightValues[] = {{"Max3p4e38", 3.4e38f}, {"FltMax", kFltMax},   {"Plus1e11", 1e11f},
                                   {"Plus1e12", 1e12f},    {"Minus1e38", -1e38f}, {"Denormal", 1e-40f},
                                   {"Mixed", kClean}};

Patch patch_of(const LightValue& v) {
  if (v.value != kClean) return [value = v.value](int, float) { return value; };
  return [](int i, float clean) {
    const float m = kMixed[size_t(i) % std::size(kMixed)];
    return m == kClean ? clean : m;
  };
}

// The sanitize rule, on the host.
float sanitized(float v) { return std::isfinite(v) && v >= 0.0f && v <= kMaxRadiance ? v : 0.0f; }

struct Case {
  size_t kind;
  ChannelId light;
  size_t value;  // into kLightValues
  Format output;
};

std::vector<Case> all_cases() {
  std::vector<Case> cases;
  for (Format output : {Format::F32, Format::F16})
    for (size_t k = 0; k < kinds().size(); ++k)
      for (ChannelId id : kinds()[k].lights)
        for (size_t v = 0; v < std::size(kLightValues); ++v) cases.push_back({k, id, v, output});
  return cases;
}

// The output format's value of `v` as passthrough converts it.
double converted(float v, Format output) {
  if (!std::isfinite(v)) return 0.0;
  if (output == Format::F32) return v;
  return test::from_half(test::to_half(std::clamp(v, -65504.0f, 65504.0f)));
}

bool same_value(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

// converge_still 0 where the pipeline has the parameter (see the header).
std::vector<pipelines::ParameterValue> without_still_mean(const std::string& pipeline) {
  for (const auto& p : pipelines::available_pipelines())
    if (p.name == pipeline)
      for (const auto& info : p.parameters)
        if (info.name == "converge_still") return {{"converge_still", 0.0}};
  return {};
}

class RadianceHardCases : public test::GpuTest, public ::testing::WithParamInterface<Case> {
 protected:
  // One session per pipeline kind and output format, reset at the start of
  // each run, and its clean run.
  struct Kind {
    std::unique_ptr<pipelines::Pipeline> session;
    std::vector<std::vector<float>> clean;
    double brightest = 0.0;
  };
  static Kind& kind_state(size_t kind, Format output) {
    Kind& k = states()[{kind, output}];
    if (!k.session) {
      k.session = open(kinds()[kind], Format::F32, output, without_still_mean(kinds()[kind].pipeline));
      for (int t = 0; t < kFrames; ++t) {
        k.clean.push_back(svgf_inputs::run(*k.session, frame(kinds()[kind], Format::F32, t == 0), output));
        for (float v : k.clean.back()) k.brightest = std::max(k.brightest, double(v));
      }
    }
    return k;
  }
  static void TearDownTestSuite() { states().clear(); }

  // The frames of one run: clean, the patch at kBadFrame, clean again.
  static std::vector<std::vector<float>> run(Kind& state, const PipelineKind& kind, ChannelId light,
                                             const Patch& patch, Format output) {
    std::vector<std::vector<float>> out;
    for (int t = 0; t < kFrames; ++t)
      out.push_back(svgf_inputs::run(
          *state.session, frame(kind, Format::F32, t == 0, light, t == kBadFrame ? patch : Patch{}), output));
    return out;
  }

 private:
  static std::map<std::pair<size_t, Format>, Kind>& states() {
    static std::map<std::pair<size_t, Format>, Kind> s;
    return s;
  }
};

std::string where(int t, int i) {
  return "frame " + std::to_string(t) + " (bad frame " + std::to_string(kBadFrame) + "), pixel (" +
         std::to_string((i / 3) % kW) + ", " + std::to_string((i / 3) / kW) + ") component " + std::to_string(i % 3);
}

TEST_P(RadianceHardCases, OutputStaysFiniteAndHistoryRecovers) {
  const Case c = GetParam();
  const PipelineKind& kind = kinds()[c.kind];
  const LightValue& value = kLightValues[c.value];
  Kind& state = kind_state(c.kind, c.output);
  ASSERT_GT(state.brightest, 0.0);
  const Patch patch = patch_of(value);
  const auto out = run(state, kind, c.light, patch, c.output);
  ASSERT_EQ(out.size(), size_t(kFrames));
  for (const auto& o : out) ASSERT_EQ(o.size(), size_t(3 * kN));

  if (std::string(kind.pipeline) == "passthrough") {
    // No sanitizing of finite values: the input as the output format holds it; non-finite is 0.
    for (int t = 0; t < kFrames; ++t) {
      const auto input = test::decode_plane(frame(kind, Format::F32, t == 0, c.light, t == kBadFrame ? patch : Patch{})
                                                .plane(c.light)
                                                .bytes,
                                            Format::F32);
      for (int i = 0; i < 3 * kN; ++i) {
        ASSERT_TRUE(same_value(out[t][i], converted(float(input[i]), c.output)))
            << where(t, i) << ": " << out[t][i] << " for input " << input[i];
        ASSERT_TRUE(std::isfinite(out[t][i])) << where(t, i) << ": " << out[t][i];
      }
    }
    return;
  }

  // The patch's values as the sanitize rule leaves them; the brightest valid one.
  bool changed = false;
  double valid_max = 0.0;
  for (int i = 0; i < 3 * 8 * 6; ++i) {
    const float v = patch(i, 1.0f);
    changed = changed || !same_value(v, sanitized(v));
    valid_max = std::max(valid_max, double(sanitized(v)));
  }
  const Patch sanitized_patch = [&patch](int i, float clean) { return sanitized(patch(i, clean)); };
  const auto expected = changed ? run(state, kind, c.light, sanitized_patch, c.output) : out;

  const double top = c.output == Format::F16 ? kHalfMax : std::numeric_limits<float>::max();
  std::vector<double> difference;  // largest |output - clean output| / brightest per frame
  for (int t = 0; t < kFrames; ++t) {
    const double allowed =
        t < kBadFrame ? 0.0 : kBoundFactor * (state.brightest + valid_max / double(t + 1));
    double worst = 0.0;
    for (int i = 0; i < 3 * kN; ++i) {
      const float v = out[t][i];
      ASSERT_TRUE(std::isfinite(v) && v >= 0.0f && v <= top) << where(t, i) << ": " << v;
      ASSERT_EQ(v, expected[t][i]) << where(t, i) << ": differs from the session given the sanitized frames";
      const double d = std::fabs(double(v) - state.clean[t][i]);
      ASSERT_LE(d, allowed) << where(t, i) << ": " << v << " against the clean session's " << state.clean[t][i]
                            << " (brightest " << state.brightest << ", brightest valid bad value " << valid_max << ")";
      worst = std::max(worst, d);
    }
    difference.push_back(worst / state.brightest);
    if (kind.stateless && t > kBadFrame) {
      EXPECT_EQ(worst, 0.0) << "frame " << t << " differs from the clean session's";
    }
  }
  std::printf("[ info     ] largest difference from the clean session per frame (of the brightest):");
  for (double d : difference) std::printf(" %.3g", d);
  std::printf("\n");
}

std::string name_of(const Case& c) {
  return std::string(kinds()[c.kind].label) + "__" + std::string(protocol::find_channel(c.light)->name) + "__" +
         kLightValues[c.value].name + (c.output == Format::F16 ? "__out_fp16" : "__out_fp32");
}
std::string case_name(const ::testing::TestParamInfo<Case>& info) { return name_of(info.param); }
void PrintTo(const Case& c, std::ostream* os) { *os << name_of(c); }

INSTANTIATE_TEST_SUITE_P(EveryPipelineLightAndValue, RadianceHardCases, ::testing::ValuesIn(all_cases()), case_name);

}  // namespace
}  // namespace dn
