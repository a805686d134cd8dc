// After a device loss every frame fails fast with DeviceFailure naming the
// VkResult, nothing crashes, and objects tear down cleanly. The loss is
// simulated by marking the context lost (a real one cannot be provoked
// portably); the code paths after detection are the same.
#include <gtest/gtest.h>

#include "frames.hpp"
#include "gpu_test_env.hpp"
#include "pipelines/pipeline.hpp"

namespace dn {
namespace {

using test::ChannelId;
using test::Format;

TEST(DeviceFailure, LostDeviceFailsFramesFastWithTheResultName) {
  gpu::ContextOptions options;
  options.device = test::test_device_selector();
  options.validation = gpu::Context::validation_layer_available();
  gpu::Context context(options);
  {
    auto pipe = pipelines::create(context, test::make_config("passthrough", 8, 4, {{ChannelId::Radiance, Format::F32}}));
    test::HostFrame f;
    f.add(ChannelId::Radiance, Format::F32, std::vector<float>(8 * 4 * 3, 1.0f));
    std::vector<uint8_t> out;
    std::vector<pipelines::PassTiming> timings;
    test::process(*pipe, f.view(), true, out, timings);

    context.mark_lost();
    for (int i = 0; i < 2; ++i) {
      try {
        test::process(*pipe, f.view(), true, out, timings);
        FAIL() << "process succeeded on a lost device";
      } catch (const pipelines::DeviceFailure& e) {
        EXPECT_NE(std::string(e.what()).find("VK_ERROR_DEVICE_LOST"), std::string::npos) << e.what();
      }
    }
  }  // the pipeline is destroyed with the context marked lost
  EXPECT_EQ(context.validation_message_count(), 0u);
}

}  // namespace
}  // namespace dn
