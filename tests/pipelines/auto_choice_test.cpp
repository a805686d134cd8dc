// "auto" per channel set: the pipeline docs/pipelines.md's table names, the
// channels it reads, and what the reason says is not used. Pure data: prepare()
// does no device work.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "pipelines/auto_choice.hpp"
#include "text_file.hpp"

namespace dn::pipelines {
namespace {

using protocol::ChannelId;
using protocol::Format;

struct AutoCase {
  const char* name;
  std::vector<ChannelId> declared;
  const char* chosen;
  const char* not_used;  // the reason's "not used: ..." list; "" when every channel is read
};

const std::vector<ChannelId> kGBuffer = {ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth,
                                         ChannelId::Motion};
const std::vector<ChannelId> kSplitGBuffer = {ChannelId::Diffuse,  ChannelId::Specular, ChannelId::Albedo,
                                              ChannelId::SpecularF0, ChannelId::Roughness, ChannelId::Normal,
                                              ChannelId::Depth,    ChannelId::Motion};
const std::vector<ChannelId> kReflectionFeatures = {ChannelId::Position,           ChannelId::ReflectionPosition,
                                                    ChannelId::ReflectionAlbedo,   ChannelId::ReflectionNormal,
                                                    ChannelId::ReflectionDepth,    ChannelId::ReflectionDirection,
                                                    ChannelId::ReflectionDistance};
const std::vector<ChannelId> kStatistics = {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2,
                                            ChannelId::StatM3};

std::vector<ChannelId> operator+(std::vector<ChannelId> a, const std::vector<ChannelId>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

SessionConfig auto_config(const std::vector<ChannelId>& ids) {
  SessionConfig c;
  c.width = 32;
  c.height = 16;
  c.pipeline = std::string(kAutoPipeline);
  for (ChannelId id : ids) c.channels.push_back({id, Format::F32});
  return c;
}

class AutoChoiceTest : public ::testing::TestWithParam<AutoCase> {};

TEST_P(AutoChoiceTest, PicksTheTablesPipelineAndNamesWhatItDoesNotRead) {
  const AutoCase& c = GetParam();
  const SessionConfig declared = auto_config(c.declared);
  auto prepared = prepare(declared);
  const auto* err = std::get_if<ConfigError>(&prepared);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  const PreparedPipeline& p = std::get<PreparedPipeline>(prepared);
  EXPECT_EQ(p.config().pipeline, c.chosen);
  EXPECT_EQ(p.declared_channels(), declared.channels);  // frames carry everything declared
  const std::string& reason = p.choice_reason();
  EXPECT_FALSE(reason.empty());
  const std::string not_used = std::string("; not used: ") + c.not_used;
  if (*c.not_used) {
    EXPECT_NE(reason.find(not_used), std::string::npos) << reason;
  } else {
    EXPECT_EQ(reason.find("not used"), std::string::npos) << reason;
  }
  // The pipeline reads the declared channels minus the unused ones, in declared order.
  size_t read = 0;
  for (const InputChannel& ch : declared.channels)
    if (read < p.config().channels.size() && p.config().channels[read] == ch) ++read;
  EXPECT_EQ(read, p.config().channels.size()) << "the pipeline's channels are not a subsequence of the declared";
  EXPECT_EQ(prepare(p.config()).index(), 0u) << "the chosen configuration does not validate as a named session";
}

INSTANTIATE_TEST_SUITE_P(
    ChannelSets, AutoChoiceTest,
    ::testing::Values(
        AutoCase{"colour", {ChannelId::Radiance}, "image", ""},
        AutoCase{"colour_albedo", {ChannelId::Radiance, ChannelId::Albedo}, "image", ""},
        AutoCase{"colour_albedo_normal", {ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal}, "image", ""},
        AutoCase{"colour_albedo_normal_depth",
                 {ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth}, "image", ""},
        AutoCase{"colour_depth", {ChannelId::Radiance, ChannelId::Depth}, "image", ""},
        AutoCase{"colour_motion", {ChannelId::Radiance, ChannelId::Motion}, "image", "motion"},
        AutoCase{"colour_depth_motion", {ChannelId::Radiance, ChannelId::Depth, ChannelId::Motion}, "image",
                 "motion"},
        AutoCase{"gbuffer_without_albedo",
                 {ChannelId::Radiance, ChannelId::Normal, ChannelId::Depth, ChannelId::Motion}, "image", "motion"},
        AutoCase{"gbuffer", kGBuffer, "svgf", ""},
        AutoCase{"gbuffer_emission", kGBuffer + std::vector{ChannelId::Emission}, "svgf", ""},
        AutoCase{"gbuffer_and_split", kGBuffer + std::vector{ChannelId::Diffuse, ChannelId::Specular}, "svgf",
                 "diffuse, specular"},
        AutoCase{"gbuffer_roughness_f0_no_split", kGBuffer + std::vector{ChannelId::SpecularF0, ChannelId::Roughness},
                 "svgf", "specular_f0"},
        AutoCase{"gbuffer_sample_count", kGBuffer + std::vector{ChannelId::SampleCount}, "progressive", ""},
        AutoCase{"colour_sample_count", {ChannelId::Radiance, ChannelId::SampleCount}, "image", "sample_count"},
        AutoCase{"split_gbuffer", kSplitGBuffer, "svgf-fb", ""},
        AutoCase{"split_gbuffer_and_radiance", kSplitGBuffer + std::vector{ChannelId::Radiance}, "svgf-fb",
                 "radiance"},
        AutoCase{"split_gbuffer_reflection_features", kSplitGBuffer + kReflectionFeatures, "reflect", ""},
        AutoCase{"split_gbuffer_some_reflection_features",
                 kSplitGBuffer + std::vector{ChannelId::ReflectionPosition}, "svgf-fb", "reflection_position"},
        AutoCase{"statistics", std::vector{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal} + kStatistics,
                 "stat", ""},
        AutoCase{"statistics_depth_motion",
                 std::vector{ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::Depth,
                             ChannelId::Motion} +
                     kStatistics,
                 "stat-temporal", ""}),
    [](const ::testing::TestParamInfo<AutoCase>& info) { return std::string(info.param.name); });

TEST(AutoChoice, TheTableNamesOnlyPipelinesThisBuildOffersAndEndsWithoutASignal) {
  const auto& rules = auto_rules();
  ASSERT_FALSE(rules.empty());
  EXPECT_TRUE(rules.back().signal.empty());
  for (const AutoRule& rule : rules) {
    bool offered = false;
    for (const auto& p : available_pipelines()) offered |= p.name == rule.pipeline;
    EXPECT_TRUE(offered) << rule.pipeline;
  }
}

TEST(AutoChoice, WithoutRadianceOrASplitPairNothingFits) {
  auto prepared = prepare(auto_config({ChannelId::Albedo, ChannelId::Normal}));
  const auto* err = std::get_if<ConfigError>(&prepared);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->problem, ConfigProblem::MissingChannel);
  EXPECT_NE(err->message.find("albedo, normal"), std::string::npos) << err->message;
}

TEST(AutoChoice, TakesNoParameters) {
  SessionConfig c = auto_config({ChannelId::Radiance});
  c.parameters = {{"iterations", 3}};
  auto prepared = prepare(c);
  const auto* err = std::get_if<ConfigError>(&prepared);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->problem, ConfigProblem::InvalidParameter);
  EXPECT_EQ(err->field, "parameters[0].name");
  EXPECT_NE(err->message.find("iterations"), std::string::npos) << err->message;
}

TEST(AutoChoice, AnUnusedChannelIsStillCheckedAsDeclared) {
  SessionConfig c = auto_config({ChannelId::Radiance, ChannelId::Motion});
  c.channels[1].format = static_cast<Format>(7);
  auto prepared = prepare(c);
  const auto* err = std::get_if<ConfigError>(&prepared);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->problem, ConfigProblem::InvalidChannel);
  EXPECT_EQ(err->field, "channels[1].format");
  c.channels = {{ChannelId::Radiance, Format::F32}, {ChannelId::Motion, Format::F32}, {ChannelId::Motion, Format::F32}};
  prepared = prepare(c);
  err = std::get_if<ConfigError>(&prepared);
  ASSERT_TRUE(err);
  EXPECT_EQ(err->field, "channels[2].id");
}

TEST(AutoChoice, AnnouncesEveryChannelItsPipelinesTakeAndRequiresNone) {
  const PipelineDescription a = auto_description();
  EXPECT_EQ(a.name, kAutoPipeline);
  EXPECT_EQ(a.required_channels, 0u);
  EXPECT_TRUE(a.parameters.empty());
  uint64_t takes = 0;
  for (const auto& p : available_pipelines())
    if (p.name != "passthrough" && p.name != "accumulate") takes |= p.required_channels | p.optional_channels;
  EXPECT_EQ(a.optional_channels, takes);
}

// docs/pipelines.md "auto" reproduces the table: one row per rule, in order.
TEST(AutoChoice, TheDocsTableIsTheCodesTable) {
  const std::string doc = test::read_text(DN_DOCS_PIPELINES_MD);
  size_t order = 0, at = 0;
  for (const AutoRule& rule : auto_rules()) {
    std::string signal;
    for (ChannelId id : rule.signal) signal += (signal.empty() ? "" : ", ") + std::string(protocol::find_channel(id)->name);
    const std::string row = "| " + std::to_string(++order) + " | `" + std::string(rule.pipeline) + "` | " +
                            (signal.empty() ? "–" : signal) + " | " + std::string(rule.reason) + " |";
    const size_t found = doc.find(row, at);
    ASSERT_NE(found, std::string::npos) << "docs/pipelines.md lacks, after the previous row, the row:\n" << row;
    at = found;
  }
}

}  // namespace
}  // namespace dn::pipelines
