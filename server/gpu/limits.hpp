// Device limits that matter before a session is created.
//
// validate() of a session configuration runs without a Context, so the
// process keeps one set of "current device limits": the Vulkan 1.2 guaranteed
// minimums until a Context is created, then the limits of the most recently
// created Context (the server holds exactly one). Thread-safe.
#pragma once

#include <cstdint>

namespace dn::gpu {

struct DeviceLimits {
  uint64_t max_storage_buffer_range = uint64_t{1} << 27;   // spec minimum: 128 MiB
  uint64_t max_memory_allocation_size = uint64_t{1} << 30; // spec minimum (maintenance3): 1 GiB
  uint32_t max_compute_work_group_count[3] = {65535, 65535, 65535};
  uint32_t max_compute_work_group_invocations = 128;
  uint32_t max_texel_buffer_elements = 65536;  // spec minimum; texel bindings (shaders/include/pass.glsl)
};

// Limits of the current device (see above).
DeviceLimits current_device_limits();

// Called by Context's constructor.
void publish_device_limits(const DeviceLimits& limits);

}  // namespace dn::gpu
