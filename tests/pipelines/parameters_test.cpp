// The parameter table (shaders/include/parameters.def) without slot numbers:
// groups, the uniform block's parameter struct, and the checks on groups.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string_view>

#include "pipelines/definitions.hpp"
#include "pipelines/frame_constants.hpp"
#include "pipelines/parameters.hpp"

namespace dn {
namespace {

using pipelines::ParameterGroups;

TEST(ParameterTable, EveryRowIsOneFloatOfTheUniformBlockInRowOrder) {
  const pipelines::Parameters p;
  const auto& table = pipelines::parameter_table();
  ASSERT_FALSE(table.empty());
  for (size_t i = 0; i < table.size(); ++i) {
    const auto offset = reinterpret_cast<const char*>(&(p.*table[i].member)) - reinterpret_cast<const char*>(&p);
    EXPECT_EQ(offset, static_cast<std::ptrdiff_t>(i * sizeof(float))) << table[i].info.name;
  }
  EXPECT_EQ(sizeof(pipelines::Parameters), (table.size() * sizeof(float) + 15) / 16 * 16);
  EXPECT_EQ(offsetof(pipelines::FrameConstants, params) % 16, 0u);
}

TEST(ParameterTable, GroupsAreDeclaredPerPipeline) {
  for (const auto& def : pipelines::definitions()) {
    SCOPED_TRACE(def.description.name);
    EXPECT_EQ(pipelines::parameters_of(def.parameter_groups).size(), def.description.parameters.size());
  }
  const std::string_view fb[] = {"svgf"};
  const auto block = pipelines::parameter_block(fb, {{"phi_colour", 4}});
  EXPECT_EQ(block.svgf_phi_colour, 4.0f);
  EXPECT_EQ(block.svgf_atrous_iterations, 4.0f);  // default
  EXPECT_EQ(block.accumulate_max_history, 0.0f);  // not a group svgf-fb takes
}

TEST(ParameterTable, UnknownGroupsAndClashingNamesAreRejected) {
  const std::string_view unknown[] = {"svgf", "svgf-fb"};  // groups are identifiers, pipelines are not
  EXPECT_THROW(pipelines::parameters_of(unknown), std::logic_error);
  const std::string_view clash[] = {"accumulate", "svgf"};  // both have max_history
  EXPECT_THROW(pipelines::parameters_of(clash), std::logic_error);
}

}  // namespace
}  // namespace dn
