#include "server/stats.hpp"

#include <algorithm>
#include <map>

#include "gpu/compute.hpp"
#include "gpu/context.hpp"
#include "gpu/pipeline_cache.hpp"
#include "gpu/transient_pool.hpp"
#include "pipelines/input_forms.hpp"
#include "server/capacity/pipeline_costs.hpp"

namespace dn::server {
namespace {

// Per pipeline: its input forms and the distinct kernels they compile (pure
// data, the same for the server's lifetime).
struct Variants {
  size_t forms = 0, kernels = 0;
};
const std::map<std::string, Variants>& variants_by_pipeline() {
  static const std::map<std::string, Variants> table = [] {
    std::map<std::string, Variants> t;
    for (const auto& p : pipelines::available_pipelines()) {
      const pipelines::KernelVariants v = pipelines::kernel_variants(p);
      t[p.name] = {v.forms, v.kernels};
    }
    return t;
  }();
  return table;
}

}  // namespace

void ServerCounters::add_frame_timings(const std::vector<pipelines::PassTiming>& timings) {
  for (const auto& t : timings) {
    auto& sum = pass_timings[t.name];
    sum.total_ms += t.milliseconds;
    ++sum.count;
  }
}

void ServerCounters::add_build(const BuiltPipeline& built) {
  ++builds.count;
  builds.total_ms += built.build_ms;
  builds.max_ms = std::max(builds.max_ms, built.build_ms);
  builds.last_ms = built.build_ms;
  builds.compile_ms += built.compile_ms;
  builds.first_run_ms += built.first_run_ms;
}

protocol::Stats make_stats(const ServerCounters& counters, const LiveState& live, gpu::Context& device) {
  protocol::Stats st;
  auto add = [&](std::string name, double v) { st.values.push_back({std::move(name), v}); };
  auto n = [](uint64_t v) { return static_cast<double>(v); };
  add("uptime_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - counters.started).count());
  add("connections", n(live.connections));
  add("connections_accepted", n(counters.connections_accepted));
  add("sessions", n(live.sessions));
  add("sessions_opened", n(counters.sessions_opened));
  add("sessions_being_built", n(live.sessions_being_built));
  add("frames_processed", n(counters.frames_processed));
  add("frames_failed", n(counters.frames_failed));
  add("frames_in_flight", n(live.frames_in_flight));
  add("bytes_in", n(counters.bytes_in_closed + live.bytes_in_open));
  add("bytes_out", n(counters.bytes_out_closed + live.bytes_out_open));
  add("device_bytes", n(live.device_bytes));  // needed by open sessions
  add("persistent_bytes", n(live.device_bytes - live.transient_bytes));
  const gpu::TransientPoolStats pool = gpu::TransientPool::of(device).stats();
  add("transient_pool_bytes", n(pool.allocated_bytes));  // scratch the device holds for all sessions
  add("transient_pool_in_use_bytes", n(pool.in_use_bytes));
  for (const auto& r : live.shared_resources) add(r.name + "_ms", r.ms);  // e.g. fb_lut_ms

  // Compiling: every kernel this device compiled, and the OPEN_SESSION builds.
  const gpu::CompileStats compiled = device.kernels().stats();
  add("kernels_compiled", n(compiled.kernels));
  add("kernel_compile_ms", compiled.total_ms);
  add("kernel_compile_max_ms", compiled.slowest_ms);
  const gpu::FirstRunStats first_runs = device.kernels().first_runs();
  add("kernel_first_runs", n(first_runs.kernels));
  add("kernel_unprepared_first_runs", n(first_runs.unprepared));  // compiled inside the shared queue on lavapipe
  add("pipeline_cache_loaded_bytes", n(device.pipeline_cache().loaded_bytes()));
  add("session_builds", n(counters.builds.count));
  add("session_build_mean_ms", counters.builds.count ? counters.builds.total_ms / n(counters.builds.count) : 0.0);
  add("session_build_max_ms", counters.builds.max_ms);
  add("session_build_last_ms", counters.builds.last_ms);
  add("session_build_compile_ms", counters.builds.compile_ms);
  add("session_build_first_run_ms", counters.builds.first_run_ms);
  add("warm_up_done", live.warm_up ? 1.0 : 0.0);
  if (live.warm_up) {
    add("warm_up_ms", live.warm_up->ms);
    add("warm_up_kernels", n(live.warm_up->kernels));
    add("warm_up_configs", n(live.warm_up->configs));
    add("warm_up_configs_offered", n(live.warm_up->offered));
  }

  // Capacity: aggregate figures for every peer (a placer sees no session of anyone else).
  const uint64_t committed = live.device_bytes + live.being_built_bytes;
  add("device_memory_budget_bytes", n(live.device_budget_bytes));
  add("device_memory_free_bytes", n(live.device_budget_bytes - std::min(live.device_budget_bytes, committed)));
  add("max_sessions", n(live.max_sessions));
  add("max_session_bytes", n(live.max_session_bytes));
  add("device_busy_fraction", counters.frame_times.busy_fraction());
  for (const PipelineCost& cost : pipeline_costs()) {
    const std::string prefix = "pipeline." + cost.pipeline + ".";
    add(prefix + "device_bytes_fixed", cost.fixed_bytes);
    add(prefix + "device_bytes_per_pixel", cost.bytes_per_pixel);
    if (const auto v = variants_by_pipeline().find(cost.pipeline); v != variants_by_pipeline().end()) {
      add(prefix + "input_forms", n(v->second.forms));
      add(prefix + "kernel_variants", n(v->second.kernels));  // every one compiled by the warm-up
    }
    // The model's session's channel_bit mask, in halves: a STATS value is a double, exact only below 2^53.
    add(prefix + "reference_channels_lo", n(cost.reference_channels & 0xFFFFFFFFu));  // ids 0-31: bit i = id i
    add(prefix + "reference_channels_hi", n(cost.reference_channels >> 32));          // ids 32-63: bit i = id 32 + i
    if (const auto ms = counters.frame_times.ms_per_megapixel(cost.pipeline)) {  // absent until measured
      add(prefix + "frame_ms_per_megapixel", *ms);
      add(prefix + "frames_measured", n(counters.frame_times.frames_measured(cost.pipeline)));
    }
  }

  for (const auto& f : live.sessions_figures) {  // lets a watcher find a session to ATTACH to
    if (st.values.size() >= 200) break;
    const std::string prefix = "session." + std::to_string(f.id) + ".";
    add(prefix + "frames", n(f.frames));
    add(prefix + "persistent_bytes_per_pixel", f.persistent_per_pixel);
    add(prefix + "transient_bytes_per_pixel", f.transient_per_pixel);
  }
  for (const auto& [name, sum] : counters.pass_timings) {
    if (st.values.size() >= 250) break;
    add("pass." + name + ".mean_ms", sum.count ? sum.total_ms / n(sum.count) : 0.0);
  }
  return st;
}

}  // namespace dn::server
