// The contract between a session and the device work of its pipeline.
// The session layer validates frames against the declared channels; a
// pipeline validates its own configuration and runs frames on the device.
// Of the protocol only the channel table (dn/protocol/channels.hpp: which
// per-pixel data exists, its components and storage) is shared; messages,
// error codes and wire fields stop at the session.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "dn/protocol/channels.hpp"

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

// One per-pixel input of a session: which channel, stored how in its planes.
struct InputChannel {
  protocol::ChannelId id = protocol::ChannelId::Radiance;
  protocol::Format format = protocol::Format::F32;
  bool operator==(const InputChannel&) const = default;
};

// A tunable set for the session, by the name a pipeline's description lists.
struct ParameterValue {
  std::string name;
  double value = 0.0;
  bool operator==(const ParameterValue&) const = default;
};

struct SessionConfig {
  uint32_t width = 0;
  uint32_t height = 0;
  std::string pipeline;
  protocol::Format output_format = protocol::Format::F32;
  std::vector<InputChannel> channels;
  std::vector<ParameterValue> parameters;
};

// What kind of mistake a refused configuration holds.
enum class ConfigProblem { UnknownPipeline, MissingChannel, InvalidChannel, InvalidParameter, LimitExceeded };

struct ConfigError {
  ConfigProblem problem = ConfigProblem::InvalidParameter;
  std::string field;    // the SessionConfig field, e.g. "parameters[0].value", "channels[2].format"
  std::string message;  // names the value and what was expected
};

// One device pass's time in a frame, or a host stage's ("upload", "download").
struct PassTiming {
  std::string name;
  double milliseconds = 0.0;
};

// How many input frames a frame's output rests on per pixel: the least and
// the lower median over the frame.
struct SampleCounts {
  uint32_t min = 0;
  uint32_t median = 0;
  bool operator==(const SampleCounts&) const = default;
};

struct GraphSpec;   // pipelines/graph.hpp
struct FrameInput;  // pipelines/frame_input.hpp

// A configuration that passed validation, with its pass graph built (once):
// what prepare() returns and create() consumes, so one OPEN_SESSION builds
// its graph once. Cheap to copy (the graph is shared and immutable).
class PreparedPipeline {
 public:
  // The pipeline's configuration: for a session opened as "auto", the chosen
  // pipeline and the declared channels it reads.
  const SessionConfig& config() const { return config_; }
  // The channels each frame carries: config().channels, or for "auto" every
  // declared channel (those the choice does not read are checked and dropped).
  const std::vector<InputChannel>& declared_channels() const {
    return declared_channels_.empty() ? config_.channels : declared_channels_;
  }
  // config() with declared_channels(): what each frame of the session carries.
  SessionConfig frame_config() const {
    SessionConfig c = config_;
    c.channels = declared_channels();
    return c;
  }
  // For "auto": why config().pipeline was chosen, one line; empty otherwise.
  const std::string& choice_reason() const { return choice_reason_; }
  // Persistent device bytes create() will allocate (= the pipeline's device_bytes()).
  uint64_t device_bytes() const { return device_bytes_; }
  const GraphSpec& graph() const { return *graph_; }
  const std::shared_ptr<const GraphSpec>& shared_graph() const { return graph_; }

 private:
  friend std::variant<PreparedPipeline, ConfigError> prepare(const SessionConfig& config);
  friend std::variant<PreparedPipeline, ConfigError> prepare_auto(const SessionConfig& declared);
  PreparedPipeline(SessionConfig config, std::shared_ptr<const GraphSpec> graph, uint64_t device_bytes)
      : config_(std::move(config)), graph_(std::move(graph)), device_bytes_(device_bytes) {}

  SessionConfig config_;
  std::vector<InputChannel> declared_channels_;  // set only for "auto"
  std::string choice_reason_;
  std::shared_ptr<const GraphSpec> graph_;
  uint64_t device_bytes_ = 0;
};

// Thrown by Pipeline::process and create() when the device fails.
struct DeviceFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Pipeline {
 public:
  virtual ~Pipeline() = default;
  // Device memory this session needs to run a frame: what it holds for its
  // lifetime (history, inputs, outputs, frame constants) plus transient_bytes().
  virtual uint64_t device_bytes() const = 0;
  // Of device_bytes(), the scratch leased from the device's transient pool
  // for each frame and shared with other sessions in between.
  virtual uint64_t transient_bytes() const { return 0; }
  uint64_t persistent_bytes() const { return device_bytes() - transient_bytes(); }
  // The session this pipeline serves.
  virtual const SessionConfig& config() const = 0;
  // Runs one frame (its planes checked by the session, frame_input.hpp).
  // Fills `output` with the Output plane (width*height*3 in the session's
  // output format) when want_output is true, and appends one timing per
  // device pass plus the host stages "upload" and "download".
  virtual void process(const FrameInput& frame, bool want_output, std::vector<uint8_t>& output,
                       std::vector<PassTiming>& timings) = 0;
  // After process(): how many input frames the last frame's output rests on
  // per pixel, over the frame (RESULT.samples); nullopt for a pipeline that
  // keeps no count.
  virtual std::optional<SampleCounts> samples() const { return std::nullopt; }
};

// Every pipeline this build offers, in a stable order.
const std::vector<PipelineDescription>& available_pipelines();

// Validates the configuration and builds its pass graph once: pipeline name
// (or "auto": auto_choice.hpp), resolution, channels (required present, no
// unknown ones), parameters (known names, in range, integral where required)
// and the largest binding against
// the current device limits (gpu::current_device_limits()). The result's
// device_bytes() is what create() allocates. Thread-safe, no device work.
std::variant<PreparedPipeline, ConfigError> prepare(const SessionConfig& config);

// Builds the pipeline's device objects from a prepared graph (no second
// build, no second validation; the largest binding is checked against this
// context's limits, DeviceFailure otherwise). Safe to call from several
// threads; process() of different pipelines may run concurrently.
std::unique_ptr<Pipeline> create(gpu::Context& context, const PreparedPipeline& prepared);

// The same three steps for callers that keep only the configuration; each
// builds the graph again (prefer prepare()).
// validate(): prepare()'s error, if any.
std::optional<ConfigError> validate(const SessionConfig& config);
// Persistent device bytes create() would allocate, so limits are enforced before allocating.
uint64_t estimate_device_bytes(const SessionConfig& config);
// Builds the pipeline's device objects; config must have passed validate()
// (std::invalid_argument otherwise).
std::unique_ptr<Pipeline> create(gpu::Context& context, const SessionConfig& config);

}  // namespace dn::pipelines
