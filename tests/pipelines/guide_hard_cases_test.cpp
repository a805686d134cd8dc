// Hard cases on the guides (docs/pipelines.md "Sanitize
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
#include "hard_case_scene.hpp"
#include "svgf_inputs.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;
using namespace hard_cases;

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
        k.clean.push_back(svgf_inputs::run(*k.session, frame(kinds()[kind], planes, t == 0)));
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
