#include "pipelines/graph.hpp"

#include "pipelines/frame_input.hpp"
#include "pipelines/sample_summary.hpp"
#include "pipelines/wire_format.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "gpu/error.hpp"

namespace dn::pipelines {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// projection * view and its inverse; both the identity when it is singular
// or not finite (a client that sends no real camera), so no pass ever reads
// NaN from them.
void view_projection(const std::array<float, 16>& view, const std::array<float, 16>& projection, float forward[16],
                     float inverse[16]) {
  glm::mat4 vp = glm::make_mat4(projection.data()) * glm::make_mat4(view.data());
  glm::mat4 inv = glm::inverse(vp);
  bool finite = std::isfinite(glm::determinant(vp)) && glm::determinant(vp) != 0.0f;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) finite = finite && std::isfinite(inv[c][r]) && std::isfinite(vp[c][r]);
  if (!finite) vp = inv = glm::mat4(1.0f);
  std::memcpy(forward, glm::value_ptr(vp), 16 * sizeof(float));
  std::memcpy(inverse, glm::value_ptr(inv), 16 * sizeof(float));
}

}  // namespace

namespace {

// The placeholder behind unbound optional bindings (one per context).
struct UnboundBinding {
  explicit UnboundBinding(gpu::Context& context)
      : buffer(context, 16, gpu::BufferKind::Storage, "unbound_optional_binding") {}
  gpu::Buffer buffer;
};

}  // namespace

const gpu::Buffer& unbound_binding_buffer(gpu::Context& context) {
  return context.shared<UnboundBinding>([&context] { return std::make_unique<UnboundBinding>(context); }).buffer;
}

GraphPipeline::Node& GraphPipeline::node(const std::string& name) {
  const BufferSpec* b = spec_->find(name);  // an alias's name reaches its buffer
  for (auto& n : nodes_)
    if (n.spec == b) return n;
  throw std::logic_error("pipeline graph: pass binds unknown buffer " + name);
}

const gpu::Buffer& GraphPipeline::bound(const BindingRef& ref, uint32_t parity) {
  if (!ref.bound()) return unbound_binding_buffer(context_);
  Node& n = node(ref.buffer);
  if (n.shared) return *n.shared;
  if (n.transient >= 0) return scratch_.buffer(static_cast<size_t>(n.transient));
  uint32_t copy = 0;
  if (n.spec->role == BufferRole::History) copy = ref.slot == Slot::Current ? parity : parity ^ 1u;
  return n.copies[copy];
}

GraphPipeline::GraphPipeline(gpu::Context& context, const SessionConfig& config,
                             std::shared_ptr<const GraphSpec> spec)
    : context_(context), config_(config), spec_(std::move(spec)) {
  try {
    nodes_.reserve(spec_->buffers.size());
    for (const auto& b : spec_->buffers) {
      Node& n = nodes_.emplace_back();
      n.spec = &b;
      if (b.role == BufferRole::Shared) {
        n.shared = &b.shared(context);
        continue;
      }
      if (b.role == BufferRole::Scratch) {
        n.transient = static_cast<int>(scratch_sizes_.size());
        scratch_sizes_.push_back(b.bytes);
        device_bytes_ += b.bytes;
        transient_bytes_ += b.bytes;
        continue;
      }
      gpu::BufferKind kind = gpu::BufferKind::Storage;
      if (b.role == BufferRole::Input || b.role == BufferRole::Constant) kind = gpu::BufferKind::StorageUpload;
      if (b.role == BufferRole::Output || b.role == BufferRole::Readback) kind = gpu::BufferKind::StorageDownload;
      n.copies[0] = gpu::Buffer(context, b.bytes, kind, b.name);
      device_bytes_ += b.bytes;
      if (b.role == BufferRole::History) {
        n.copies[1] = gpu::Buffer(context, b.bytes, kind, b.name + "[1]");
        device_bytes_ += b.bytes;
      }
      if (b.role == BufferRole::Constant) {
        n.copies[0].write(b.data);
        constants_staged_ = constants_staged_ || n.copies[0].staged();
      }
    }
    constants_ = gpu::Buffer(context, GraphSpec::kConstantBytes, gpu::BufferKind::Constants, "frame_constants");
    device_bytes_ += GraphSpec::kConstantBytes;

    uint32_t storage_total = 0;
    for (const auto& p : spec_->passes) storage_total += static_cast<uint32_t>(p.bindings().size());
    descriptors_ = std::make_unique<gpu::DescriptorPool>(context, 2 * static_cast<uint32_t>(spec_->passes.size()),
                                                         2 * storage_total);

    // Sets are written with scratch leased now; lease_scratch() repoints them
    // when a later frame gets other buffers.
    if (!scratch_sizes_.empty()) {
      scratch_ = gpu::TransientPool::of(context).lease(scratch_sizes_);
      held_ids_ = scratch_.ids();
    }
    const uint64_t pixels = uint64_t{spec_->width} * spec_->height;
    for (const auto& ps : spec_->passes) {
      Pass& pass = passes_.emplace_back();
      pass.spec = &ps;
      pass.kernel = context.kernels().get(kernel_desc(ps, kWorkgroupSize));
      for (const auto& ref : ps.bindings())
        pass.binds_transient = pass.binds_transient || (ref.bound() && node(ref.buffer).transient >= 0);
      check_texel_limit(pass);
      for (uint32_t parity = 0; parity < 2; ++parity)
        pass.sets[parity] = descriptors_->allocate(*pass.kernel, constants_.handle(), storage_of(pass, parity));

      if (ps.grid) continue;  // 2-D: Kernel::record_dispatch sizes it from the grid
      const uint64_t items =
          ps.invocations ? ps.invocations : (pixels + ps.pixels_per_invocation - 1) / ps.pixels_per_invocation;
      const uint64_t groups = std::max<uint64_t>(1, (items + kWorkgroupSize - 1) / kWorkgroupSize);
      const uint64_t gx = std::min<uint64_t>(groups, context.limits().max_compute_work_group_count[0]);
      const uint64_t gy = (groups + gx - 1) / gx;
      if (gy > context.limits().max_compute_work_group_count[1])
        throw DeviceFailure("pass " + ps.name() + ": " + std::to_string(groups) + " workgroups exceed the device limit");
      pass.groups_x = static_cast<uint32_t>(gx);
      pass.groups_y = static_cast<uint32_t>(gy);
    }

    commands_ = std::make_unique<gpu::CommandStream>(context);
    timestamps_ = std::make_unique<gpu::TimestampPool>(context, static_cast<uint32_t>(spec_->passes.size()) + 3);
    scratch_.release();  // nothing runs yet: other sessions may use it until our first frame
  } catch (const gpu::Error& e) {
    throw DeviceFailure(std::string("creating pipeline ") + config.pipeline + ": " + e.what());
  }
}

void GraphPipeline::check_texel_limit(const Pass& pass) {
  const auto& decls = pass.spec->declaration().bindings;
  for (size_t i = 0; i < decls.size(); ++i) {
    if (decls[i].access != shaders::Access::texel || !pass.spec->bindings()[i].bound()) continue;
    const uint64_t texels = bound(pass.spec->bindings()[i], 0).size() / texel_bytes(decls[i].element);
    if (texels > context_.limits().max_texel_buffer_elements)
      throw DeviceFailure("pass " + pass.spec->name() + " reads " + pass.spec->bindings()[i].buffer + " (" +
                          std::to_string(texels) + " elements) through a texel buffer; the device allows " +
                          std::to_string(context_.limits().max_texel_buffer_elements));
  }
}

std::vector<VkBuffer> GraphPipeline::storage_of(const Pass& pass, uint32_t parity) {
  std::vector<VkBuffer> storage;
  for (const auto& ref : pass.spec->bindings()) storage.push_back(bound(ref, parity).handle());
  return storage;
}

void GraphPipeline::lease_scratch() {
  if (scratch_sizes_.empty() || !scratch_.empty()) return;  // none, or still held after a failed frame
  scratch_ = gpu::TransientPool::of(context_).lease(scratch_sizes_, held_ids_);
  if (scratch_.ids() == held_ids_) return;
  // The sets are idle: the previous frame's submission has completed.
  for (const Pass& pass : passes_)
    if (pass.binds_transient)
      for (uint32_t parity = 0; parity < 2; ++parity)
        descriptors_->write(pass.sets[parity], *pass.kernel, constants_.handle(), storage_of(pass, parity));
  held_ids_ = scratch_.ids();
}

GraphPipeline::~GraphPipeline() {
  // The command stream waits for a pending submission before anything it
  // uses is destroyed (members are destroyed in reverse order).
  commands_.reset();
}

void GraphPipeline::process(const FrameInput& frame, bool want_output, std::vector<uint8_t>& output,
                            std::vector<pipelines::PassTiming>& timings) {
  std::lock_guard lock(mutex_);
  try {
    run(frame, want_output, output, timings);
  } catch (const gpu::Error& e) {
    history_valid_ = false;
    throw DeviceFailure(e.what());
  } catch (...) {
    history_valid_ = false;
    throw;
  }
}

void GraphPipeline::run(const FrameInput& frame, bool want_output, std::vector<uint8_t>& output,
                        std::vector<pipelines::PassTiming>& timings) {
  if (context_.lost()) throw gpu::VulkanError(VK_ERROR_DEVICE_LOST, "process");

  // Upload: planes are copied into their (mapped or staging) buffers as fp32.
  const auto upload_start = Clock::now();
  bool any_staged_input = false;
  for (auto& n : nodes_) {
    if (n.spec->role != BufferRole::Input) continue;
    const std::span<const uint8_t> bytes = frame.planes.at(n.spec->plane);
    if (bytes.size() != n.spec->plane_bytes) throw std::logic_error("a FrameInput plane of the wrong size");
    if (n.spec->format == protocol::Format::F16)
      n.copies[0].write_with(n.spec->bytes, [&](uint8_t* dst) {
        widen_halves(bytes.data(), bytes.size() / 2, reinterpret_cast<float*>(dst));
      });
    else
      n.copies[0].write(bytes);
    any_staged_input = any_staged_input || n.copies[0].staged();
  }

  const bool reset = frame.reset || !history_valid_;
  FrameConstants constants{};
  constants.size[0] = spec_->width;
  constants.size[1] = spec_->height;
  constants.size[2] = spec_->width * spec_->height;
  constants.size[3] = reset ? kFrameFlagReset : 0u;
  constants.motion[0] = frame.motion_to_previous_pixels[0];
  constants.motion[1] = frame.motion_to_previous_pixels[1];
  constants.params = spec_->parameters;
  std::memcpy(constants.previous_view_projection, view_projection_, sizeof view_projection_);
  view_projection(frame.view, frame.projection, view_projection_, constants.inverse_view_projection);
  constants_.write({reinterpret_cast<const uint8_t*>(&constants), sizeof constants});
  const double upload_host_ms = ms_since(upload_start);

  const uint32_t parity = static_cast<uint32_t>(frames_ & 1);
  Node* out_node = nullptr;
  for (auto& n : nodes_)
    if (n.spec->role == BufferRole::Output) out_node = &n;

  lease_scratch();
  VkCommandBuffer cmd = commands_->begin();
  timestamps_->reset(cmd);
  // Orders this frame after everything the previous submissions did to the
  // same buffers (history written last frame, staging copies).
  gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                      VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                      VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT |
                          VK_ACCESS_TRANSFER_WRITE_BIT);
  timestamps_->write(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0);
  bool any_readback = false;
  for (auto& n : nodes_)
    if (n.spec->role == BufferRole::Readback) {
      vkCmdFillBuffer(cmd, n.copies[0].handle(), 0, VK_WHOLE_SIZE, 0);
      any_readback = true;
    }
  if (any_staged_input || constants_staged_ || any_readback) {
    for (auto& n : nodes_) {
      if (n.spec->role == BufferRole::Input) n.copies[0].record_upload(cmd, n.spec->bytes);
      if (n.spec->role == BufferRole::Constant && constants_staged_) n.copies[0].record_upload(cmd, n.spec->bytes);
    }
    gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_ACCESS_TRANSFER_WRITE_BIT,
                        VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
  }
  timestamps_->write(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 1);

  uint32_t mark = 2;
  for (size_t i = 0; i < passes_.size(); ++i) {
    const Pass& pass = passes_[i];
    if (i > 0)
      gpu::memory_barrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT,
                          VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT);
    if (pass.spec->grid) {
      pass.kernel->record_dispatch(cmd, pass.sets[parity], pass.spec->grid->push);
    } else {
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pass.kernel->pipeline());
      vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pass.kernel->layout(), 0, 1, &pass.sets[parity], 0,
                              nullptr);
      vkCmdDispatch(cmd, pass.groups_x, pass.groups_y, 1);
    }
    timestamps_->write(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, mark++);
    record_captures(cmd, pass, parity);
  }

  if (want_output && out_node) {
    out_node->copies[0].record_readback(cmd, out_node->spec->bytes, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                                        VK_ACCESS_SHADER_WRITE_BIT);
  }
  for (auto& n : nodes_)
    if (n.spec->role == BufferRole::Readback)
      n.copies[0].record_readback(cmd, n.spec->bytes, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
  timestamps_->write(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, mark++);

  commands_->submit_and_wait(first_use_ ? gpu::CommandStream::kFirstUseTimeoutNs
                                        : gpu::CommandStream::kDefaultTimeoutNs);
  first_use_ = false;
  scratch_.release();  // the frame's work is done: other sessions may lease it now
  const std::vector<double> intervals = timestamps_->read_intervals_ms(mark);

  double download_ms = 0.0;
  if (want_output && out_node) {
    download_ms = intervals.back();  // staging copy, if any
    const auto t0 = Clock::now();
    const BufferSpec& out = *out_node->spec;
    output.resize(out.plane_bytes);
    if (out.format == protocol::Format::F16)
      out_node->copies[0].read_with(out.bytes, [&](const uint8_t* src) {
        narrow_to_halves(reinterpret_cast<const float*>(src), out.plane_bytes / 2, output.data());
      });
    else
      out_node->copies[0].read(output);
    download_ms += ms_since(t0);
  }

  for (auto& n : nodes_)
    if (n.spec->role == BufferRole::Readback) {
      n.read.resize(n.spec->bytes);
      n.copies[0].read(n.read);
    }

  timings.push_back({"upload", upload_host_ms + intervals[0]});
  for (size_t i = 0; i < passes_.size(); ++i) timings.push_back({passes_[i].spec->name(), intervals[i + 1]});
  timings.push_back({"download", download_ms});

  ++frames_;
  history_valid_ = true;
  constants_staged_ = false;  // the device copy is made
}

std::optional<pipelines::SampleCounts> GraphPipeline::samples() const {
  for (const auto& n : nodes_)
    if (n.spec->role == BufferRole::Readback && n.spec->name == kSampleSummary && !n.read.empty())
      return decode_sample_summary(n.read);
  return std::nullopt;
}

}  // namespace dn::pipelines
