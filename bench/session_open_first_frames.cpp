// After the server's warm-up: every pipeline in every input form, fp32 and
// fp16, opened once; its first frame's time on the server (the RESULT's
// timings: upload, device passes, download) against its steady state (median
// of frames 2-4). A first frame that compiles a kernel takes seconds on
// lavapipe, a steady one milliseconds. Prints one row per form and the STATS
// compile counters before and after; exits 1 when a first frame exceeds 3x
// its steady state or a kernel was compiled (bench/session_open.sh runs it).
//
//   session_open_first_frames --server tcp://127.0.0.1:7878 [--size 256x144]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "dn/client/client.hpp"
#include "pipelines/input_forms.hpp"

namespace {

using dn::protocol::ChannelId;
using dn::protocol::Format;

struct Form {
  std::string pipeline, name;  // name: the channels beyond the pipeline's required ones
  std::vector<ChannelId> channels;
};

// The server's own list (pipelines/input_forms.hpp): the forms its warm-up
// covers are exactly the ones opened here.
std::vector<Form> input_forms() {
  std::vector<Form> forms;
  for (const dn::pipelines::PipelineDescription& p : dn::pipelines::available_pipelines())
    for (uint64_t mask : dn::pipelines::input_forms(p)) {
      Form form{p.name, "", {}};
      for (const auto& c : dn::protocol::kChannels) {
        if (!(mask & dn::protocol::channel_bit(c.id))) continue;
        form.channels.push_back(c.id);
        if (!(p.required_channels & dn::protocol::channel_bit(c.id)))
          form.name += (form.name.empty() ? "" : "+") + std::string(c.name);
      }
      if (form.name.empty()) form.name = "required channels";
      forms.push_back(std::move(form));
    }
  return forms;
}

std::map<std::string, double> stats(dn::client::Connection& c) {
  std::map<std::string, double> out;
  for (const auto& v : c.stats().values) out[v.name] = v.value;
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  std::string server = "tcp://127.0.0.1:7878";
  uint32_t width = 256, height = 144;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--server") server = value;
    else if (flag == "--size") std::sscanf(value.c_str(), "%ux%u", &width, &height);
    else {
      std::fprintf(stderr, "unknown flag %s\n", flag.c_str());
      return 2;
    }
  }
  auto conn = dn::client::Connection::connect(server);
  while (stats(conn)["warm_up_done"] != 1.0) std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto before = stats(conn);

  // Every plane 0.5 in every component (fp16 0.5 = 0x3800): a lit, in-front surface everywhere.
  const size_t pixels = size_t{width} * height;
  const std::vector<float> f32(pixels * 4, 0.5f);
  const std::vector<uint16_t> f16(pixels * 4, 0x3800);
  bool ok = true;
  std::printf("| pipeline | input form | planes | first frame ms | steady ms (median of frames 2-4) | ratio |\n");
  std::printf("|---|---|---|---|---|---|\n");
  for (Format format : {Format::F32, Format::F16}) {
    for (const Form& form : input_forms()) {
      dn::client::SessionDesc d;
      d.width = width;
      d.height = height;
      d.pipeline = form.pipeline;
      d.output_format = format;
      for (ChannelId id : form.channels)
        d.channel(id, dn::protocol::is_sample_statistic(id) ? Format::F32 : format);
      auto session = conn.open_session(d);
      std::vector<double> ms;
      for (int frame = 0; frame < 5; ++frame) {
        dn::client::FrameInput in;
        for (const auto& c : d.channels) {
          const size_t bytes = pixels * dn::protocol::find_channel(c.id)->components *
                               (c.format == Format::F16 ? 2 : 4);
          in.add(c.id, c.format, c.format == Format::F16 ? static_cast<const void*>(f16.data()) : f32.data(), bytes);
        }
        ms.push_back(session.denoise(in).total_timing_ms());
      }
      const double steady = median({ms[2], ms[3], ms[4]});
      const double ratio = ms[0] / steady;
      ok = ok && ratio <= 3.0;
      std::printf("| %s | %s | %s | %.2f | %.2f | %.2f%s |\n", form.pipeline.c_str(), form.name.c_str(),
                  format == Format::F16 ? "fp16" : "fp32", ms[0], steady, ratio, ratio > 3.0 ? " **over 3x**" : "");
      std::fflush(stdout);
      session.close();
    }
  }
  const auto after = stats(conn);
  const double compiled = after.at("kernels_compiled") - before.at("kernels_compiled");
  const double unprepared = after.at("kernel_unprepared_first_runs") - before.at("kernel_unprepared_first_runs");
  std::printf("\nwarm-up: %.0f of %.0f configurations, %.0f kernels, %.0f ms; afterwards: %.0f kernels compiled, "
              "%.0f unprepared first runs\n",
              before.at("warm_up_configs"), before.at("warm_up_configs_offered"), before.at("warm_up_kernels"),
              before.at("warm_up_ms"), compiled, unprepared);
  ok = ok && compiled == 0 && unprepared == 0;
  return ok ? 0 : 1;
}
