// passthrough's description: radiance, no parameters.
#include "descriptions.hpp"

namespace dn {
namespace {

TEST(PassthroughDescription, RadianceAndNoParameters) {
  const auto& d = test::description("passthrough");
  EXPECT_EQ(d.required_channels, test::bits({protocol::ChannelId::Radiance}));
  EXPECT_TRUE(d.parameters.empty());
}

}  // namespace
}  // namespace dn
