// A session's first frame against a real dnserver process: after the warm-up
// no input form compiles a kernel, and a kernel that is new to the device is
// run once off the shared queue before the session opens, so it never
// compiles inside the queue another session's frames wait on.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <thread>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

namespace fs = std::filesystem;
using protocol::ChannelId;
using protocol::Format;

struct Form {
  std::string pipeline;
  std::vector<ChannelId> channels;
};

// Every input form a client can open, written out here rather than taken from
// the server (docs/server.md, "warm-up"; docs/protocol.md §7.6 for extra
// samples): radiance or the split pair with each signal in radiance or
// lighting form, the extras each pipeline requires, and each optional
// channel the pipeline reads present or not: emission (svgf, svgf-fb,
// reflect, progressive), roughness (svgf), reflection_footprint (reflect),
// sample_count (progressive), the sample statistics (stat-temporal), albedo,
// normal and depth (image), and 0 to 3 extra samples with radiance or diffuse + specular (svgf, svgf-fb, reflect).
std::vector<Form> input_forms() {
  using C = ChannelId;
  using F = protocol::SampleField;
  const std::vector<C> gbuffer = {C::Albedo, C::Normal, C::Depth, C::Motion};
  const std::vector<std::vector<C>> svgf_signals = {{C::Radiance},
                                                   {C::Diffuse, C::Specular},
                                                   {C::Diffuse, C::SpecularLighting, C::SpecularAlbedo},
                                                   {C::DiffuseLighting, C::Specular},
                                                   {C::DiffuseLighting, C::SpecularLighting, C::SpecularAlbedo}};
  const std::vector<std::vector<C>> fb_signals = {{C::Diffuse, C::Specular}, {C::DiffuseLighting, C::Specular}};
  const std::vector<C> fb_extra = {C::SpecularF0, C::Roughness};
  const std::vector<C> reflection = {C::Position,        C::ReflectionPosition, C::ReflectionAlbedo,
                                     C::ReflectionNormal, C::ReflectionDepth,   C::ReflectionDirection,
                                     C::ReflectionDistance};
  const std::vector<C> statistics = {C::StatCount, C::StatMean, C::StatM2, C::StatM3};
  const std::vector<C> stat_frame = {C::Radiance, C::Albedo, C::Normal};
  auto join = [](std::initializer_list<std::vector<C>> parts) {
    std::vector<C> out;
    for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
    return out;
  };
  // Every subset of `optional` added to `base`.
  auto with_subsets = [](const std::vector<C>& base, const std::vector<C>& optional) {
    std::vector<std::vector<C>> out;
    for (size_t subset = 0; subset < (size_t{1} << optional.size()); ++subset) {
      std::vector<C> form = base;
      for (size_t i = 0; i < optional.size(); ++i)
        if (subset >> i & 1) form.push_back(optional[i]);
      out.push_back(form);
    }
    return out;
  };
  // 0 to 3 extra samples of a signal form: only radiance or diffuse + specular take them.
  auto with_samples = [](const std::vector<C>& signals) {
    std::vector<F> colours;
    if (signals == std::vector<C>{C::Radiance}) colours = {F::Radiance};
    if (signals == std::vector<C>{C::Diffuse, C::Specular}) colours = {F::Diffuse, F::Specular};
    std::vector<std::vector<C>> out = {{}};
    for (uint32_t k = 1; !colours.empty() && k <= 3; ++k) {
      std::vector<C> samples;
      for (uint32_t j = 1; j <= k; ++j) {
        for (F f : colours) samples.push_back(protocol::sample_channel(j, f));
        for (F f : {F::Normal, F::Depth, F::Offset}) samples.push_back(protocol::sample_channel(j, f));
      }
      out.push_back(samples);
    }
    return out;
  };
  std::vector<Form> forms = {{"passthrough", {C::Radiance}},
                             {"accumulate", {C::Radiance, C::Normal, C::Depth, C::Motion}},
                             {"stat", join({stat_frame, statistics})},
                             {"stat-temporal", join({stat_frame, statistics, {C::Depth, C::Motion}})},
                             {"stat-temporal", join({stat_frame, {C::Depth, C::Motion}})}};
  for (const auto& guides : with_subsets({C::Radiance}, {C::Albedo, C::Normal, C::Depth}))
    forms.push_back({"image", guides});
  for (const auto& s : svgf_signals) {
    for (const auto& extras : with_subsets(join({s, gbuffer}), {C::Emission, C::Roughness}))
      for (const auto& samples : with_samples(s)) forms.push_back({"svgf", join({extras, samples})});
    for (const auto& extras : with_subsets(join({s, gbuffer}), {C::Emission, C::SampleCount}))
      forms.push_back({"progressive", extras});
  }
  for (const auto& s : fb_signals)
    for (const auto& samples : with_samples(s)) {
      for (const auto& extras : with_subsets(join({s, gbuffer, fb_extra}), {C::Emission}))
        forms.push_back({"svgf-fb", join({extras, samples})});
      for (const auto& extras : with_subsets(join({s, gbuffer, fb_extra, reflection}), {C::Emission, C::ReflectionFootprint}))
        forms.push_back({"reflect", join({extras, samples})});
    }
  return forms;
}

protocol::OpenSession session_of(const Form& form, Format format, uint32_t width, uint32_t height) {
  protocol::OpenSession o;
  o.width = width;
  o.height = height;
  o.pipeline = form.pipeline;
  o.output_format = format;
  for (ChannelId id : form.channels)  // sample statistics are fp32 only
    o.channels.push_back({id, protocol::is_sample_statistic(id) ? Format::F32 : format});
  return o;
}

std::string describe(const protocol::OpenSession& o) {
  std::string s = o.pipeline + (o.output_format == Format::F16 ? " fp16:" : " fp32:");
  for (const auto& c : o.channels) s += " " + std::string(protocol::find_channel(c.id)->name);
  return s;
}

// The next message that is not the server's keep-alive PING (answered with PONG).
std::optional<Received> receive_reply(RawClient& c, double timeout_s) {
  for (;;) {
    auto r = c.receive(timeout_s);
    if (!r) return r;
    auto* ping = std::get_if<protocol::Ping>(&r->message);
    if (!ping) return r;
    c.send(protocol::Pong{ping->payload}, r->header.request_id);
  }
}

// Opens the session, sends one frame and waits for its RESULT; fails the test on anything else.
void open_and_run_one_frame(RawClient& c, const protocol::OpenSession& request, uint64_t request_id) {
  // RawClient::open waits 20 s; a build with a run on the private device takes longer on a cold cache.
  c.send(request, request_id);
  auto reply = receive_reply(c, 600.0);
  ASSERT_TRUE(reply) << describe(request);
  auto* opened = std::get_if<protocol::Session>(&reply->message);
  ASSERT_NE(opened, nullptr) << describe(request) << ": " << protocol::to_string(reply->header.type);
  const protocol::Session session = *opened;
  auto f = make_frame(session.session_id, 0, request.width, request.height, request.channels, 0.5f);
  c.send(f.frame, request_id + 1);
  // Generous: a cold kernel compiles on the private device during the open,
  // but a loaded 2-core machine may still be slow.
  auto r = receive_reply(c, 300.0);
  ASSERT_TRUE(r) << describe(request);
  ASSERT_TRUE(std::get_if<protocol::Result>(&r->message)) << describe(request) << ": "
                                                          << protocol::to_string(r->header.type);
  c.send(protocol::CloseSession{session.session_id}, request_id + 2);
  auto closed = receive_reply(c, 60.0);
  ASSERT_TRUE(closed) << describe(request);
  EXPECT_TRUE(std::get_if<protocol::SessionClosed>(&closed->message)) << protocol::to_string(closed->header.type);
}

std::map<std::string, double> wait_for_warm_up(RawClient& c) {
  std::map<std::string, double> st;
  for (int i = 0; i < 9000; ++i) {  // up to 15 minutes: every form with a cold Mesa cache on a loaded machine
    st = stats(c);
    if (st.at("warm_up_done") == 1.0) break;
    ::usleep(100000);
  }
  return st;
}

// After the warm-up, every pipeline in every input form, fp32 and fp16, opens
// and runs its first frame without compiling a kernel or running one for the
// first time: the warm-up built and dispatched every one (on lavapipe a
// kernel compiles at its first dispatch). The server counts the same forms.
TEST(FirstFrame, AfterTheWarmUpNoInputFormCompilesAKernel) {
  ServerProcess server({"--warm-up", "--no-disk-cache"});
  RawClient c(server.tcp_url());
  c.hello();
  const auto warm = wait_for_warm_up(c);
  ASSERT_EQ(warm.at("warm_up_done"), 1.0);
  const auto forms = input_forms();
  std::map<std::string, double> forms_of;
  for (const Form& form : forms) ++forms_of[form.pipeline];
  for (const auto& [pipeline, n] : forms_of) EXPECT_EQ(warm.at("pipeline." + pipeline + ".input_forms"), n) << pipeline;
  // Every pipeline the server offers has its forms written out here.
  for (const auto& [name, value] : warm) {
    const bool forms_key =
        name.rfind("pipeline.", 0) == 0 && name.size() > 21 && name.compare(name.size() - 12, 12, ".input_forms") == 0;
    if (forms_key) {
      EXPECT_TRUE(forms_of.count(name.substr(9, name.size() - 21))) << name << ": no input forms in this test";
    }
  }
  EXPECT_GT(warm.at("warm_up_configs_offered"), 0.0);
  EXPECT_EQ(warm.at("warm_up_configs"), warm.at("warm_up_configs_offered"));  // none refused
  EXPECT_EQ(server.log().find("level=warn event=warm_up"), std::string::npos) << server.log();

  uint64_t id = 10;
  for (Format format : {Format::F32, Format::F16})
    for (const Form& form : forms) {
      // The warm-up's size class (lavapipe compiles anew for frames below about 64x64).
      open_and_run_one_frame(c, session_of(form, format, 256, 144), id);
      id += 10;
    }
  const auto after = stats(c);
  EXPECT_EQ(after.at("kernels_compiled"), warm.at("kernels_compiled"));
  EXPECT_EQ(after.at("kernel_first_runs"), warm.at("kernel_first_runs"));
  EXPECT_EQ(after.at("kernel_unprepared_first_runs"), warm.at("kernel_unprepared_first_runs"));
  EXPECT_EQ(after.at("session_build_first_run_ms"), 0.0);  // nothing was new to the device
  EXPECT_EQ(after.at("frames_failed"), 0.0);

  // A frame size the warm-up did not run: lavapipe may make new machine code
  // for it, so the kernels run first on a private device, once per size.
  const Form& passthrough = forms.front();
  ASSERT_EQ(passthrough.pipeline, "passthrough");
  open_and_run_one_frame(c, session_of(passthrough, Format::F32, 48, 36), id);
  const auto small = stats(c);
  EXPECT_GT(small.at("session_build_first_run_ms"), 0.0);
  EXPECT_EQ(small.at("kernels_compiled"), warm.at("kernels_compiled"));  // same kernels, new size
  open_and_run_one_frame(c, session_of(passthrough, Format::F32, 48, 36), id + 10);
  EXPECT_EQ(stats(c).at("session_build_first_run_ms"), small.at("session_build_first_run_ms"));
  EXPECT_EQ(stats(c).at("frames_failed"), 0.0);
}

// Without a warm-up and with a cold Mesa shader cache, each pipeline in each
// input form opens while another session streams: every kernel new to the
// device runs first on a private device (Mesa's shader cache carries its
// machine code), so no kernel runs for the first time unprepared inside the
// shared queue, where the streaming session's frames would wait behind it.
TEST(FirstFrame, NewKernelsRunOffTheSharedQueueBeforeTheSessionOpens) {
  const fs::path mesa_cache = fs::temp_directory_path() / ("dn-mesa-cache-" + std::to_string(::getpid()));
  fs::remove_all(mesa_cache);
  ::setenv("MESA_SHADER_CACHE_DIR", mesa_cache.c_str(), 1);  // cold, but on
  ::unsetenv("MESA_SHADER_CACHE_DISABLE");
  ServerProcess server({"--no-warm-up", "--no-disk-cache"});
  ::unsetenv("MESA_SHADER_CACHE_DIR");

  RawClient c(server.tcp_url());
  c.hello();
  const double unprepared_at_start = stats(c).at("kernel_unprepared_first_runs");  // start-up's shared tables

  RawClient streamer(server.tcp_url());
  streamer.hello();
  const auto stream_request = passthrough_session(32, 16);
  streamer.send(stream_request, 1);
  auto stream_reply = receive_reply(streamer, 600.0);  // its kernels, too, run first on a private device
  ASSERT_TRUE(stream_reply);
  ASSERT_TRUE(std::get_if<protocol::Session>(&stream_reply->message));
  const uint64_t stream_id = std::get<protocol::Session>(stream_reply->message).session_id;
  std::atomic<bool> stop{false};
  std::atomic<int> streamed{0}, stream_failures{0};
  std::thread stream([&] {
    for (uint64_t i = 0; !stop; ++i) {
      auto f = make_frame(stream_id, i, 32, 16, stream_request.channels, 0.25f);
      streamer.send(f.frame, 100 + i);
      auto r = receive_reply(streamer, 300.0);
      if (!r || !std::get_if<protocol::Result>(&r->message)) {
        ++stream_failures;
        return;
      }
      ++streamed;
    }
  });

  uint64_t id = 10;
  for (const Form& form : input_forms()) {
    open_and_run_one_frame(c, session_of(form, Format::F32, 32, 16), id);
    id += 10;
  }
  stop = true;
  stream.join();

  const auto st = stats(c);
  EXPECT_EQ(stream_failures.load(), 0);
  EXPECT_GT(streamed.load(), 0);
  EXPECT_GT(st.at("kernel_first_runs"), 0.0);
  EXPECT_GT(st.at("session_build_first_run_ms"), 0.0);
  EXPECT_EQ(st.at("kernel_unprepared_first_runs"), unprepared_at_start) << server.log();
  EXPECT_EQ(st.at("frames_failed"), 0.0);
  fs::remove_all(mesa_cache);
}

}  // namespace
}  // namespace dn::test
