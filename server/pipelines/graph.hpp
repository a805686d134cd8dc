// The generic layer under every pipeline: a pipeline is a list of passes
// over named device buffers. A GraphSpec is pure data computed from a
// SessionConfig (so estimate_device_bytes() and the limit check need no
// device); GraphPipeline turns it into device objects and runs frames.
//
// Buffers:
//  - Input:   one client plane, held as fp32 whatever the client sends
//             (wire_format.hpp: an fp16 plane is widened as it is uploaded)
//  - Output:  the Output plane, written as fp32 by the last pass and
//             narrowed to the session's output format as it is read back
//  - History: persistent per-session state, allocated twice and ping-ponged:
//             a pass binds the Current or the Previous copy, and the two
//             descriptor sets of each pass swap them on alternate frames
//  - Scratch: transient device-only intermediate, written and read within one
//             frame: leased per frame from the device's gpu::TransientPool and
//             shared with other sessions between their frames, so a pass must
//             write every scratch element it later reads in the same frame
//  - Persistent: per-session state kept across frames in a single copy (no
//             ping-pong): for state whose every read in a frame comes before
//             the pass that overwrites it (Slot is ignored)
//  - Constant: per-session read-only data the definition computes on the
//             host from the session's parameters (a table), uploaded once
//             before the first frame
//  - Readback: a small per-session buffer the host reads after every frame
//             (a pass's summary of the frame, e.g. sample_summary.hpp's),
//             zeroed before the frame's first pass
// Every binding of a pass is a storage buffer, bound by the name its shader
// declares (pass.hpp); binding 0 is the FrameConstants buffer.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "gpu/buffer.hpp"
#include "gpu/commands.hpp"
#include "gpu/compute.hpp"
#include "gpu/levels.hpp"
#include "gpu/context.hpp"
#include "gpu/timestamps.hpp"
#include "gpu/transient_pool.hpp"
#include "pipelines/frame_constants.hpp"
#include "pipelines/parameters.hpp"
#include "pipelines/pass.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::pipelines {

// Shared: a read-only device buffer the context holds for every session
// (BufferSpec::shared gives it); bound, never allocated or counted per session.
enum class BufferRole { Input, Output, History, Scratch, Persistent, Shared, Constant, Readback };

// A context-wide resource: made on first use, then the same buffer for every
// session of that context (e.g. fb_lut_buffer, the F_beta table).
using SharedResource = const gpu::Buffer& (*)(gpu::Context& context);
// A pipeline's declaration of a shared resource it binds (PipelineDefinition::shared_resources).
struct SharedResourceDecl {
  const char* name;  // the graph buffer's name
  SharedResource resource;
};

struct BufferSpec {
  std::string name;
  BufferRole role = BufferRole::Scratch;
  uint64_t bytes = 0;                                    // allocation size (rounded up to 4; Input/Output: the fp32 plane)
  bool sized_by_bindings = false;                        // bytes come from its bindings' DN_PER_PIXEL rules
  uint64_t plane_bytes = 0;                              // Input/Output: the plane's size on the wire
  protocol::ChannelId channel = protocol::ChannelId::Radiance;  // Input/Output
  protocol::Format format = protocol::Format::F32;       // Input/Output: on the wire
  size_t plane = 0;                                      // Input: its index in FrameInput::planes
  SharedResource shared = nullptr;                       // Shared
  std::vector<uint8_t> data;                             // Constant: its contents
};

// A second name for a buffer whose contents are dead by the time the name is
// first bound (GraphSpec::add_alias): the name says what it holds then.
struct BufferAlias {
  std::string name;
  std::string of;
};

struct GraphSpec {
  uint32_t width = 0, height = 0;
  std::vector<BufferSpec> buffers;
  std::vector<BufferAlias> aliases;
  std::vector<PassSpec> passes;
  Parameters parameters;

  static constexpr uint64_t kConstantBytes = sizeof(FrameConstants);
  // The Output plane's buffer, as add_output() names it.
  static constexpr const char* kOutput = "output";

  // Device bytes a session needs: every buffer (History twice) plus the
  // constants buffer; of which transient_bytes() are Scratch, leased per frame.
  uint64_t device_bytes() const;
  uint64_t transient_bytes() const;
  // The largest single binding (what maxStorageBufferRange limits).
  const BufferSpec* largest_binding() const;
  // The buffer `name` names, through an alias too.
  const BufferSpec* find(const std::string& name) const;

  // Builders used by pipeline definitions.
  void add_input(const SessionConfig& config, protocol::ChannelId channel, std::string name);
  void add_output(const SessionConfig& config);
  // A buffer over the session's pixels, sized by size_from_bindings() from
  // the DN_PER_PIXEL rules of the bindings that bind it (its .pass files).
  void add_history(std::string name);
  void add_persistent(std::string name);
  void add_scratch(std::string name);
  // Scratch of a size given here, for a buffer no binding sizes.
  void add_scratch(std::string name, uint64_t bytes_per_pixel);
  // Scratch over another grid than the session's: a reduced resolution (a
  // level(), e.g. 1/2 or 1/3), or elements = pyramid_pixels() for a packed pyramid.
  void add_scratch_elements(std::string name, uint64_t elements, uint64_t bytes_per_element);
  // Level `level` of the session's resolution reduced by `factor` per level
  // (gpu/levels.hpp: each level rounds up; level 0 is the full resolution).
  gpu::Extent level(uint32_t factor, uint32_t level) const;
  void add_shared(std::string name, SharedResource resource);
  void add_constant(std::string name, std::vector<uint8_t> data);
  void add_readback(std::string name, uint64_t bytes);
  // Binds of `name` reach buffer `of` (no memory of its own): for reusing
  // scratch whose contents are dead. check() refuses a pass that binds `of`
  // by its own name at or after the first pass that binds `name`.
  void add_alias(std::string name, std::string of);

  // Appends a pass running `shader`; bind and set on the result (the
  // reference is valid until the next add_pass).
  PassSpec& add_pass(std::string name, std::string_view shader);

  // Sizes every buffer added without a size from the DN_PER_PIXEL rules of
  // the bindings that bind it (through aliases too). Throws std::logic_error
  // when no binding of it declares one or two disagree, naming them.
  void size_from_bindings();

  // The build-time check of the whole graph: buffer names unique, every
  // required binding bound, every bound buffer defined, Previous slots only
  // on History buffers, aliases only over dead contents, every buffer sized
  // (size_from_bindings() ran). Throws
  // std::logic_error naming the pass and binding.
  void check() const;

 private:
  // A buffer of `bytes` (rounded up to 4) in `role`: what the add_* builders share.
  void add_sized(std::string name, BufferRole role, uint64_t bytes);
};

uint64_t round_up4(uint64_t bytes);
// The declared format of a channel (F32 if it is not declared).
protocol::Format channel_format(const SessionConfig& config, protocol::ChannelId channel);
// Whether the session declared the channel.
bool has_channel(const SessionConfig& config, protocol::ChannelId channel);
// The declared channels as a protocol::channel_bit mask.
uint64_t channel_mask(const SessionConfig& config);

// The context's buffer for optional bindings a pass leaves unbound (the
// shader does not touch them): one small placeholder, never a real buffer
// standing in for another.
const gpu::Buffer& unbound_binding_buffer(gpu::Context& context);

class GraphPipeline final : public Pipeline {
 public:
  // spec must have passed GraphSpec::check().
  GraphPipeline(gpu::Context& context, const SessionConfig& config, std::shared_ptr<const GraphSpec> spec);
  ~GraphPipeline() override;

  uint64_t device_bytes() const override { return device_bytes_; }
  uint64_t transient_bytes() const override { return transient_bytes_; }
  const SessionConfig& config() const override { return config_; }
  void process(const FrameInput& frame, bool want_output, std::vector<uint8_t>& output,
               std::vector<pipelines::PassTiming>& timings) override;
  std::optional<pipelines::SampleCounts> samples() const override;

  const GraphSpec& spec() const { return *spec_; }

  // Inspection for tests and debugging (the server never turns it on): while
  // on, every binding of every pass except Input planes is copied right
  // after the pass into a host-readable buffer; captured() returns those
  // bytes for the last completed frame. Costs one copy per binding per pass.
  void set_capture(bool on);
  // The bytes of `buffer` as pass `pass` left them in the last frame;
  // throws std::out_of_range when that pass does not bind that buffer.
  std::vector<uint8_t> captured(const std::string& pass, const std::string& buffer) const;

 private:
  struct Node {
    const BufferSpec* spec = nullptr;
    gpu::Buffer copies[2];               // History: [parity]; otherwise copies[0] only
    const gpu::Buffer* shared = nullptr;  // Shared: the context's buffer
    int transient = -1;                   // Scratch: its index in the frame's lease
    std::vector<uint8_t> read;            // Readback: its bytes after the last frame
  };
  struct Capture {
    std::string buffer;
    Slot slot = Slot::Current;
    gpu::Buffer copy;
  };
  struct Pass {
    const PassSpec* spec = nullptr;
    std::vector<Capture> captures;  // set_capture(true) only
    std::shared_ptr<const gpu::Kernel> kernel;
    VkDescriptorSet sets[2] = {VK_NULL_HANDLE, VK_NULL_HANDLE};  // [parity]
    bool binds_transient = false;  // its sets are rewritten when the leased scratch changes
    uint32_t groups_x = 1, groups_y = 1;
  };

  void run(const FrameInput& frame, bool want_output, std::vector<uint8_t>& output,
           std::vector<pipelines::PassTiming>& timings);
  Node& node(const std::string& name);
  const gpu::Buffer& bound(const BindingRef& ref, uint32_t parity);
  void record_captures(VkCommandBuffer cmd, const Pass& pass, uint32_t parity);
  // Leases this frame's scratch (the buffers held last frame when they are
  // free) and points the descriptor sets at them if they changed.
  void lease_scratch();
  std::vector<VkBuffer> storage_of(const Pass& pass, uint32_t parity);
  // DeviceFailure when a texel binding's buffer has more elements than the device views.
  void check_texel_limit(const Pass& pass);

  gpu::Context& context_;
  SessionConfig config_;
  std::shared_ptr<const GraphSpec> spec_;
  std::vector<Node> nodes_;
  gpu::Buffer constants_;
  std::unique_ptr<gpu::DescriptorPool> descriptors_;
  std::vector<Pass> passes_;
  std::unique_ptr<gpu::CommandStream> commands_;
  bool first_use_ = true;  // no frame submitted yet: its wait includes the shader compiles
  std::unique_ptr<gpu::TimestampPool> timestamps_;
  uint64_t device_bytes_ = 0;
  uint64_t transient_bytes_ = 0;
  std::vector<uint64_t> scratch_sizes_;  // by Node::transient
  std::vector<uint64_t> held_ids_;       // the pool ids the descriptor sets point at
  // Held from lease_scratch() until the frame's work has completed; kept when
  // a frame fails (its work may still be pending) and reused by the next.
  gpu::TransientPool::Lease scratch_;
  uint64_t frames_ = 0;          // frames completed; parity = frames_ % 2
  // projection * view of the last frame sent (FrameConstants::previous_view_projection).
  float view_projection_[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  bool history_valid_ = false;   // false until a frame completed, and after any failure
  bool constants_staged_ = false;  // a staged Constant still needs its device copy
  std::mutex mutex_;
};

}  // namespace dn::pipelines
