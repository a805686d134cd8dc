// The contract between a session and the device work of its pipeline.
// The session layer validates frames against the declared channels; a
// pipeline validates its own configuration and runs frames on the device.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"

namespace dn::gpu {
class Context;
}

namespace dn::pipelines {

struct ParameterInfo {
  std::string name;
  double default_value = 0.0;
  double min_value = 0.0;
  double max_value = 0.0;
  bool integer = false;
  std::string description;
};

struct PipelineDescription {
  std::string name;
  std::string summary;
  uint64_t required_channels = 0;  // protocol::channel_bit mask
  uint64_t optional_channels = 0;
  std::vector<ParameterInfo> parameters;
};

struct SessionConfig {
  uint32_t width = 0;
  uint32_t height = 0;
  std::string pipeline;
  protocol::Format output_format = protocol::Format::F32;
  std::vector<protocol::ChannelDecl> channels;
  std::vector<protocol::Parameter> parameters;
};

struct ConfigError {
  protocol::ErrorCode code = protocol::ErrorCode::InvalidParameter;
  std::string field;    // e.g. "OPEN_SESSION.parameters[0].value"
  std::string message;  // names the value and what was expected
};

// Thrown by Pipeline::process and create() when the device fails.
struct DeviceFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Pipeline {
 public:
  virtual ~Pipeline() = default;
  // Persistent device memory held by this session (history, inputs, outputs).
  virtual uint64_t device_bytes() const = 0;
  // Runs one frame. The caller guarantees every declared channel is present
  // exactly once with width*height*components bytes in its declared format.
  // Fills `output` with the Output plane (width*height*3 in the session's
  // output format) when want_output is true, and appends one timing per
  // device pass plus the host stages "upload" and "download".
  virtual void process(const protocol::Frame& frame, bool want_output, std::vector<uint8_t>& output,
                       std::vector<protocol::PassTiming>& timings) = 0;
};

// Every pipeline this build offers, in a stable order.
const std::vector<PipelineDescription>& available_pipelines();

// Checks pipeline name, resolution, channels (required present, no unknown
// ones) and parameters (known names, in range, integral where required).
std::optional<ConfigError> validate(const SessionConfig& config);

// Persistent device bytes create() would allocate, so limits are enforced before allocating.
uint64_t estimate_device_bytes(const SessionConfig& config);

// Builds the pipeline's device objects; config must have passed validate().
// Safe to call from several threads; process() of different pipelines may run concurrently.
std::unique_ptr<Pipeline> create(gpu::Context& context, const SessionConfig& config);

}  // namespace dn::pipelines
