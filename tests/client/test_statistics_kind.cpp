// dn denoise tells a pipeline that a file's sample statistics are
// demodulated (client/tools/statistics_kind.cpp; docs/client.md, "Sample
// statistics"): from dnrender's dn.stat_samples attribute to the session's
// parameter demodulated, refusing contradictions.
#include <gtest/gtest.h>

#include "args.hpp"
#include "statistics_kind.hpp"

namespace dn::cli {
namespace {

using protocol::ChannelId;

std::vector<ResolvedChannel> plan_of(std::initializer_list<ChannelId> ids) {
  std::vector<ResolvedChannel> plan;
  for (ChannelId id : ids) plan.push_back(ResolvedChannel{id, {}, {}, Convert::None, false});
  return plan;
}

const std::vector<ResolvedChannel> kWithStatistics =
    plan_of({ChannelId::Radiance, ChannelId::Albedo, ChannelId::Normal, ChannelId::StatCount, ChannelId::StatMean,
             ChannelId::StatM2, ChannelId::StatM3});

protocol::PipelineInfo stat_pipeline() {
  protocol::PipelineInfo p;
  p.name = "stat";
  p.required_channels = protocol::channel_bit(ChannelId::StatCount);
  p.parameters.push_back({"radius", 20, 1, 64, true, ""});
  p.parameters.push_back({"demodulated", 0, 0, 1, true, ""});
  return p;
}

TEST(StatisticsKind, DemodulatedFileSetsTheParameter) {
  const protocol::PipelineInfo stat = stat_pipeline();
  std::vector<protocol::Parameter> params = {{"radius", 6}};
  apply_statistics_kind(std::string("demodulated"), "f.exr", kWithStatistics, &stat, params);
  ASSERT_EQ(params.size(), 2u);
  EXPECT_EQ(params[1].name, "demodulated");
  EXPECT_EQ(params[1].value, 1.0);
}

TEST(StatisticsKind, RadianceFileOrNoAttributeOrNoStatisticsSentSetNothing) {
  const protocol::PipelineInfo stat = stat_pipeline();
  std::vector<protocol::Parameter> params;
  apply_statistics_kind(std::string("radiance"), "f.exr", kWithStatistics, &stat, params);
  apply_statistics_kind(std::nullopt, "f.exr", kWithStatistics, &stat, params);
  apply_statistics_kind(std::string("demodulated"), "f.exr", plan_of({ChannelId::Radiance}), &stat, params);
  EXPECT_TRUE(params.empty());
}

TEST(StatisticsKind, AnExplicitParameterMustAgreeWithTheFile) {
  const protocol::PipelineInfo stat = stat_pipeline();
  std::vector<protocol::Parameter> agree = {{"demodulated", 1}};
  apply_statistics_kind(std::string("demodulated"), "f.exr", kWithStatistics, &stat, agree);
  EXPECT_EQ(agree.size(), 1u);  // not added twice
  std::vector<protocol::Parameter> contradicts = {{"demodulated", 0}};
  try {
    apply_statistics_kind(std::string("demodulated"), "f.exr", kWithStatistics, &stat, contradicts);
    FAIL() << "a contradiction was accepted";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("f.exr"), std::string::npos) << e.what();
  }
  std::vector<protocol::Parameter> on_radiance = {{"demodulated", 1}};
  EXPECT_THROW(apply_statistics_kind(std::string("radiance"), "f.exr", kWithStatistics, &stat, on_radiance),
               UsageError);
}

TEST(StatisticsKind, AnUnknownKindIsAnErrorNamingTheFileAndTheValue) {
  const protocol::PipelineInfo stat = stat_pipeline();
  std::vector<protocol::Parameter> params;
  try {
    apply_statistics_kind(std::string("irradiance"), "in/f_0003.exr", kWithStatistics, &stat, params);
    FAIL() << "an unknown dn.stat_samples was accepted";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("in/f_0003.exr"), std::string::npos) << what;
    EXPECT_NE(what.find("irradiance"), std::string::npos) << what;
  }
}

// A pipeline that needs the statistics but cannot be told they are
// demodulated would misread them: refused. One that only carries them
// (passthrough: optional, no such parameter) gets nothing.
TEST(StatisticsKind, APipelineWithoutTheParameter) {
  protocol::PipelineInfo old_stat = stat_pipeline();
  old_stat.parameters.pop_back();
  std::vector<protocol::Parameter> params;
  EXPECT_THROW(apply_statistics_kind(std::string("demodulated"), "f.exr", kWithStatistics, &old_stat, params),
               std::runtime_error);
  protocol::PipelineInfo passthrough;
  passthrough.name = "passthrough";
  passthrough.optional_channels = protocol::channel_bit(ChannelId::StatCount);
  apply_statistics_kind(std::string("demodulated"), "f.exr", kWithStatistics, &passthrough, params);
  EXPECT_TRUE(params.empty());
}

}  // namespace
}  // namespace dn::cli
