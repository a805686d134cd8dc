// Shared by tests/gpu and tests/pipelines: one Context per test binary on
// lavapipe (or DN_TEST_DEVICE), with the validation layer (and
// synchronization validation) when it is installed (DN_TEST_VALIDATION=0: off); GpuTest fails any test
// during which the layer reported a message.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>

#include "gpu/context.hpp"

namespace dn::test {

// DN_TEST_DEVICE when set; else "llvmpipe" when lavapipe is present; else the default choice.
inline std::string test_device_selector() {
  if (const char* env = std::getenv("DN_TEST_DEVICE")) return env;
  for (const auto& d : gpu::Context::list_devices())
    if (d.name.find("llvmpipe") != std::string::npos) return "llvmpipe";
  return "";
}

inline gpu::ContextOptions test_context_options() {
  gpu::ContextOptions options;
  options.device = test_device_selector();
  // DN_TEST_VALIDATION=0 turns the layer off (timing runs).
  const char* env = std::getenv("DN_TEST_VALIDATION");
  options.validation = gpu::Context::validation_layer_available() && !(env && std::string(env) == "0");
  options.synchronization_validation = options.validation;
  return options;
}

inline gpu::Context& context() {
  static std::unique_ptr<gpu::Context> ctx = std::make_unique<gpu::Context>(test_context_options());
  return *ctx;
}

// A second context on the same device whose upload/download buffers go
// through staging buffers (the path of discrete GPUs).
inline gpu::Context& staging_context() {
  static std::unique_ptr<gpu::Context> ctx = [] {
    gpu::ContextOptions options = test_context_options();
    options.force_staging = true;
    return std::make_unique<gpu::Context>(options);
  }();
  return *ctx;
}

class GpuTest : public ::testing::Test {
 protected:
  void SetUp() override { messages_before_ = context().validation_message_count(); }
  void TearDown() override {
    const uint64_t now = context().validation_message_count();
    EXPECT_EQ(now, messages_before_) << "validation layer messages during the test; last: "
                                     << (context().validation_messages().empty()
                                             ? std::string("-")
                                             : context().validation_messages().back());
  }
  // For tests that also use staging_context().
  static void expect_no_messages(const gpu::Context& c) {
    EXPECT_EQ(c.validation_message_count(), 0u)
        << (c.validation_messages().empty() ? std::string("-") : c.validation_messages().back());
  }
  gpu::Context& ctx() { return context(); }

 private:
  uint64_t messages_before_ = 0;
};

}  // namespace dn::test
