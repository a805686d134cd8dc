// Additions to the pipeline contract (pipeline.hpp) for the server and tests.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "gpu/limits.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

// Largest width or height any pipeline accepts (validate() rejects more with LimitExceeded).
inline constexpr uint32_t kMaxDimension = 16384;

struct BindingSize {
  std::string buffer;  // name of the largest device buffer
  uint64_t bytes = 0;
};

// The largest single storage binding create() would make for this config
// (what maxStorageBufferRange limits). config.pipeline must be known.
BindingSize largest_binding(const SessionConfig& config);

// LimitExceeded when the largest binding exceeds limits.max_storage_buffer_range.
// validate() calls it with gpu::current_device_limits() (the limits of the
// most recently created Context, or the Vulkan minimum of 128 MiB before any).
std::optional<ConfigError> check_device_limits(const SessionConfig& config, const gpu::DeviceLimits& limits);

// Pass graphs built by this process so far (each prepare(), estimate and
// create(context, config) builds one; create(context, prepared) none). For
// the test that one OPEN_SESSION through prepare() builds its graph once.
uint64_t graphs_built_count();

struct SharedResourceTiming {
  std::string name;  // as declared ("fb_lut")
  double ms = 0.0;   // wall clock of making it: compiling its kernel and computing it on the device
};

// Makes every shared resource any pipeline declares (the F_beta table, ...)
// on this context now instead of on the first session that binds it, once per
// context; returns what each took, the same list on every call. Throws what
// making one throws (gpu::Error).
const std::vector<SharedResourceTiming>& prepare_shared_resources(gpu::Context& context);

}  // namespace dn::pipelines
