// validate(), available_pipelines(), the parameter table, device-byte
// accounting and the device-limit check.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <regex>
#include <sstream>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/graph.hpp"
#include "pipelines/parameters.hpp"
#include "pipelines/pipeline.hpp"
#include "pipelines/sample_summary.hpp"
#include "pipelines/registry.hpp"
#include "text_file.hpp"

namespace dn {
namespace {

using pipelines::ConfigProblem;
using test::ChannelId;
using test::Format;

void expect_error(const pipelines::SessionConfig& config, ConfigProblem code, const std::string& field,
                  const std::string& message_part) {
  const auto err = pipelines::validate(config);
  ASSERT_TRUE(err.has_value()) << "accepted: " << field;
  EXPECT_EQ(err->problem, code) << err->message;
  EXPECT_EQ(err->field, field) << err->message;
  EXPECT_NE(err->message.find(message_part), std::string::npos) << err->message;
}

// The registry: every DN_PIPELINE(family, id) row of pipelines.def is
// offered, in row order, named by its id with '-' for '_' (each family's
// description is checked by tests/pipelines/<family>/*_description_test.cpp).
TEST(Pipelines, AvailableAreTheRowsOfPipelinesDef) {
  std::ifstream in(DN_PIPELINES_DEF);
  ASSERT_TRUE(in) << "cannot open " << DN_PIPELINES_DEF;
  std::vector<std::string> rows;
  const std::regex row(R"(^DN_PIPELINE\([a-z0-9_]+, *([a-z0-9_]+)\))");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (!std::regex_search(line, m, row)) continue;
    std::string name = m[1];
    std::replace(name.begin(), name.end(), '_', '-');
    rows.push_back(name);
  }
  EXPECT_GE(rows.size(), 2u);  // passthrough and accumulate at least: the transport and temporal baselines
  std::vector<std::string> offered;
  for (const auto& d : pipelines::available_pipelines()) offered.push_back(d.name);
  EXPECT_EQ(offered, rows);
}

TEST(Pipelines, ParameterDefaultsAreTheSpecifiedOnes) {
  const auto slots = pipelines::resolve_parameters("accumulate", {});
  EXPECT_FLOAT_EQ(slots[0], 0.05f);
  EXPECT_FLOAT_EQ(slots[1], 32.0f);
  EXPECT_FLOAT_EQ(slots[2], 0.1f);
  EXPECT_FLOAT_EQ(slots[3], 0.9f);
  const auto custom = pipelines::resolve_parameters("accumulate", {{"max_history", 8}});
  EXPECT_FLOAT_EQ(custom[1], 8.0f);
  EXPECT_FLOAT_EQ(custom[0], 0.05f);
}

TEST(Validate, AcceptsValidConfigurations) {
  EXPECT_FALSE(pipelines::validate(test::accumulate_config(256, 144)).has_value());
  EXPECT_FALSE(pipelines::validate(test::accumulate_config(1, 1, Format::F16, Format::F16,
                                                           {{"alpha_min", 0}, {"max_history", 1024}}))
                   .has_value());
  EXPECT_FALSE(
      pipelines::validate(test::make_config("passthrough", 3840, 2160, {{ChannelId::Radiance, Format::F16}})).has_value());
}

TEST(Validate, RejectsUnknownPipeline) {
  auto c = test::accumulate_config(8, 8);
  c.pipeline = "svgf-next";
  expect_error(c, ConfigProblem::UnknownPipeline, "pipeline", "svgf-next");
}

TEST(Validate, RejectsBadResolutionAndOutputFormat) {
  expect_error(test::accumulate_config(0, 8), ConfigProblem::InvalidParameter, "width", "width");
  expect_error(test::accumulate_config(8, 0), ConfigProblem::InvalidParameter, "height", "height");
  expect_error(test::accumulate_config(20000, 8), ConfigProblem::LimitExceeded, "width", "20000");
  auto c = test::accumulate_config(8, 8);
  c.output_format = static_cast<Format>(7);
  expect_error(c, ConfigProblem::InvalidParameter, "output_format", "7");
}

TEST(Validate, RejectsMissingRequiredChannel) {
  auto c = test::accumulate_config(8, 8);
  c.channels.erase(c.channels.begin() + 1);  // normal
  expect_error(c, ConfigProblem::MissingChannel, "channels", "normal");
  expect_error(test::make_config("passthrough", 8, 8, {}), ConfigProblem::MissingChannel, "channels",
               "radiance");
}

// stat-temporal takes the four statistics planes or none: some of them is a
// renderer that lost a pass, not one without statistics.
TEST(Validate, StatTemporalTakesAllStatisticsOrNone) {
  std::vector<pipelines::InputChannel> base = {{ChannelId::Radiance, Format::F32}, {ChannelId::Albedo, Format::F32},
                                             {ChannelId::Normal, Format::F32},   {ChannelId::Depth, Format::F32},
                                             {ChannelId::Motion, Format::F32}};
  EXPECT_FALSE(pipelines::validate(test::make_config("stat-temporal", 8, 8, base)).has_value());
  auto all = base;
  for (ChannelId id : {ChannelId::StatCount, ChannelId::StatMean, ChannelId::StatM2, ChannelId::StatM3})
    all.push_back({id, Format::F32});
  EXPECT_FALSE(pipelines::validate(test::make_config("stat-temporal", 8, 8, all)).has_value());
  auto some = all;
  some.pop_back();  // stat_m3
  expect_error(test::make_config("stat-temporal", 8, 8, some), ConfigProblem::MissingChannel, "channels",
               "all four of stat_count");
  // stat needs them: one frame's single sample has no variance to test.
  expect_error(test::make_config("stat", 8, 8, {base[0], base[1], base[2]}), ConfigProblem::MissingChannel,
               "channels", "stat_count");
}

TEST(Validate, RejectsUnusedDuplicateAndMalformedChannels) {
  // accumulate has no use for albedo (passthrough accepts every input channel, for transport benchmarks).
  auto c = test::make_config("accumulate", 8, 8,
                             {{ChannelId::Radiance, Format::F32}, {ChannelId::Albedo, Format::F32},
                              {ChannelId::Normal, Format::F32}, {ChannelId::Depth, Format::F32},
                              {ChannelId::Motion, Format::F32}});
  expect_error(c, ConfigProblem::InvalidChannel, "channels[1].id", "albedo");
  c = test::make_config("passthrough", 8, 8, {{ChannelId::Radiance, Format::F32}, {ChannelId::Radiance, Format::F16}});
  expect_error(c, ConfigProblem::InvalidChannel, "channels[1].id", "twice");
  c = test::make_config("passthrough", 8, 8, {{ChannelId::Output, Format::F32}});
  expect_error(c, ConfigProblem::InvalidChannel, "channels[0].id", "32");
  c = test::make_config("passthrough", 8, 8, {{static_cast<ChannelId>(55), Format::F32}});
  expect_error(c, ConfigProblem::InvalidChannel, "channels[0].id", "55");
  c = test::make_config("passthrough", 8, 8, {{ChannelId::Radiance, static_cast<Format>(3)}});
  expect_error(c, ConfigProblem::InvalidChannel, "channels[0].format", "radiance");
}

TEST(Validate, RejectsUnknownParameter) {
  expect_error(test::accumulate_config(8, 8, Format::F32, Format::F32, {{"alpha_min", 0.1}, {"phi_colour", 10}}),
               ConfigProblem::InvalidParameter, "parameters[1].name", "phi_colour");
  expect_error(test::make_config("passthrough", 8, 8, {{ChannelId::Radiance, Format::F32}}, Format::F32,
                                 {{"alpha_min", 0.1}}),
               ConfigProblem::InvalidParameter, "parameters[0].name", "alpha_min");
  expect_error(test::accumulate_config(8, 8, Format::F32, Format::F32, {{"alpha_min", 0.1}, {"alpha_min", 0.2}}),
               ConfigProblem::InvalidParameter, "parameters[1].name", "twice");
}

TEST(Validate, RejectsOutOfRangeAndNonIntegralParameters) {
  expect_error(test::accumulate_config(8, 8, Format::F32, Format::F32, {{"alpha_min", 1.5}}),
               ConfigProblem::InvalidParameter, "parameters[0].value", "alpha_min");
  expect_error(test::accumulate_config(8, 8, Format::F32, Format::F32, {{"depth_tolerance", 0.2}, {"max_history", 0}}),
               ConfigProblem::InvalidParameter, "parameters[1].value", "max_history");
  expect_error(test::accumulate_config(8, 8, Format::F32, Format::F32, {{"max_history", 7.5}}),
               ConfigProblem::InvalidParameter, "parameters[0].value", "integer");
  expect_error(test::accumulate_config(8, 8, Format::F32, Format::F32, {{"normal_threshold", NAN}}),
               ConfigProblem::InvalidParameter, "parameters[0].value", "normal_threshold");
  expect_error(test::accumulate_config(8, 8, Format::F32, Format::F32, {{"normal_threshold", -1.01}}),
               ConfigProblem::InvalidParameter, "parameters[0].value", "-1.01");
}

// The largest accumulate binding is a 16-byte-per-pixel history buffer.
TEST(Validate, RespectsTheStorageBindingLimit) {
  gpu::DeviceLimits lavapipe;
  lavapipe.max_storage_buffer_range = uint64_t{128} << 20;
  EXPECT_FALSE(pipelines::check_device_limits(test::accumulate_config(3840, 2160), lavapipe).has_value());
  const auto err = pipelines::check_device_limits(test::accumulate_config(4096, 4096), lavapipe);
  ASSERT_TRUE(err.has_value());
  EXPECT_EQ(err->problem, ConfigProblem::LimitExceeded);
  EXPECT_EQ(err->field, "width");
  EXPECT_NE(err->message.find("history_colour"), std::string::npos) << err->message;
  EXPECT_EQ(pipelines::largest_binding(test::accumulate_config(4096, 4096)).bytes, uint64_t{4096} * 4096 * 16);
  // validate() uses the current device limits (at least the Vulkan minimum of 128 MiB).
  if (gpu::current_device_limits().max_storage_buffer_range < uint64_t{4096} * 4096 * 16) {
    EXPECT_TRUE(pipelines::validate(test::accumulate_config(4096, 4096)).has_value());
  }
}

class DeviceBytesTest : public test::GpuTest {};

TEST_F(DeviceBytesTest, EstimateEqualsAllocatedBytes) {
  const std::vector<pipelines::SessionConfig> configs = {
      test::accumulate_config(64, 48),
      test::accumulate_config(33, 17, Format::F16, Format::F16),
      test::accumulate_config(256, 144, Format::F16, Format::F32),
      test::make_config("passthrough", 31, 7, {{ChannelId::Radiance, Format::F16}}, Format::F16),
      test::make_config("passthrough", 256, 144, {{ChannelId::Radiance, Format::F32}}),
  };
  for (const auto& c : configs) {
    SCOPED_TRACE(c.pipeline + " " + std::to_string(c.width) + "x" + std::to_string(c.height));
    auto p = pipelines::create(ctx(), c);
    EXPECT_EQ(p->device_bytes(), pipelines::estimate_device_bytes(c));
  }
  // accumulate, fp32 everywhere: inputs 12+12+4+8, history 2*(16+16), output 12 = 112 B/px, + the constants block (FrameConstants).
  EXPECT_EQ(pipelines::estimate_device_bytes(test::accumulate_config(64, 48)), 64u * 48 * 112 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  // fp16 planes and output: the same 112 B/px (planes are fp32 on the device, widened at upload).
  EXPECT_EQ(pipelines::estimate_device_bytes(test::accumulate_config(64, 48, Format::F16, Format::F16)),
            64u * 48 * 112 + pipelines::GraphSpec::kConstantBytes +
            pipelines::kSampleSummaryBytes);
  EXPECT_EQ(pipelines::estimate_device_bytes(
                test::make_config("passthrough", 3, 1, {{ChannelId::Radiance, Format::F16}}, Format::F16)),
            2u * 36 + pipelines::GraphSpec::kConstantBytes);
}

TEST_F(DeviceBytesTest, CreateRejectsConfigurationsValidateRejects) {
  auto c = test::accumulate_config(8, 8);
  c.parameters = {{"max_history", 0.5}};
  EXPECT_THROW(pipelines::create(ctx(), c), std::invalid_argument);
}

// docs/pipelines.md reproduces parameters.def: every parameter appears in a
// table row "| `name` | default | min – max | ...".
TEST(Docs, ParameterTableMatchesTheDefinition) {
  const std::string doc = test::read_text(DN_DOCS_PIPELINES_MD);
  auto fmt = [](double v) {
    std::ostringstream o;
    o << v;
    return o.str();
  };
  for (const auto& row : pipelines::parameter_table()) {
    const std::string line = "| `" + row.info.name + "` | " + fmt(row.info.default_value) + " | " +
                             fmt(row.info.min_value) + " – " + fmt(row.info.max_value) + " | " +
                             (row.info.integer ? "integer" : "real") + " | " + row.info.description + " |";
    EXPECT_NE(doc.find(line), std::string::npos) << "docs/pipelines.md lacks the row:\n" << line;
  }
}

}  // namespace
}  // namespace dn
