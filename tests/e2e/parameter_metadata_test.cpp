// Parameter metadata against a real dnserver (protocol 1.1, docs/protocol.md
// §5.2.1): the tables a 1.1 client gets, the 1.0 payload a 1.0 client gets,
// and the `dn` commands that show and use them.
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <set>
#include <sstream>

#include "command.hpp"
#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

namespace fs = std::filesystem;

const protocol::PipelineInfo* find(const protocol::Welcome& w, const std::string& name) {
  for (const auto& p : w.pipelines)
    if (p.name == name) return &p;
  return nullptr;
}

const protocol::ParameterInfo* find(const protocol::PipelineInfo& p, const std::string& name) {
  for (const auto& q : p.parameters)
    if (q.name == name) return &q;
  return nullptr;
}

// Reads exactly n bytes or fails the test.
std::vector<uint8_t> read_exactly(int fd, size_t n) {
  std::vector<uint8_t> out(n);
  size_t got = 0;
  while (got < n) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 20000) <= 0) break;
    const ssize_t r = ::recv(fd, out.data() + got, n - got, 0);
    if (r <= 0) break;
    got += size_t(r);
  }
  EXPECT_EQ(got, n) << "connection ended early";
  out.resize(got);
  return out;
}

// The line of `text` that starts with `prefix`, or "".
std::string line_starting(const std::string& text, const std::string& prefix) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(prefix, 0) == 0) return line;
  return {};
}

TEST(ParameterMetadata, OneOneClientGetsEveryPipelinesTable) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  const protocol::Welcome w = c.hello();
  ASSERT_TRUE(w.has_parameters);
  // Facts from docs/pipelines.md.
  const protocol::PipelineInfo* passthrough = find(w, "passthrough");
  const protocol::PipelineInfo* accumulate = find(w, "accumulate");
  const protocol::PipelineInfo* svgf = find(w, "svgf");
  const protocol::PipelineInfo* svgf_fb = find(w, "svgf-fb");
  ASSERT_TRUE(passthrough && accumulate && svgf && svgf_fb);
  EXPECT_TRUE(passthrough->parameters.empty());
  const protocol::ParameterInfo* max_history = find(*accumulate, "max_history");
  ASSERT_NE(max_history, nullptr);
  EXPECT_EQ(max_history->default_value, 32.0);
  EXPECT_EQ(max_history->min_value, 1.0);
  EXPECT_EQ(max_history->max_value, 1024.0);
  EXPECT_TRUE(max_history->integer);
  const protocol::ParameterInfo* iterations = find(*svgf, "atrous_iterations");
  ASSERT_NE(iterations, nullptr);
  EXPECT_EQ(iterations->default_value, 4.0);
  EXPECT_EQ(iterations->min_value, 0.0);
  EXPECT_EQ(iterations->max_value, 8.0);
  EXPECT_TRUE(iterations->integer);
  const protocol::ParameterInfo* alpha = find(*svgf, "alpha_colour");
  ASSERT_NE(alpha, nullptr);
  EXPECT_EQ(alpha->default_value, 0.05);
  EXPECT_FALSE(alpha->integer);
  EXPECT_NE(alpha->description.find("temporal blend weight"), std::string::npos) << alpha->description;
  EXPECT_EQ(find(*svgf, "alpha"), nullptr);  // the name docs/client.md once used
  // svgf-fb takes svgf's parameters (the group svgf).
  ASSERT_EQ(svgf_fb->parameters.size(), svgf->parameters.size());
  for (const auto& q : svgf->parameters) EXPECT_NE(find(*svgf_fb, q.name), nullptr) << q.name;
  for (const auto& p : w.pipelines)
    for (const auto& q : p.parameters) {
      EXPECT_FALSE(q.description.empty()) << p.name << "." << q.name;
      EXPECT_LE(q.description.size(), 512u) << p.name << "." << q.name;
    }
  // The size stays far below the 65536-byte WELCOME limit.
  const size_t payload = protocol::encode(w).size() - protocol::kHeaderSize;
  size_t entries = 0, longest = 0;
  for (const auto& p : w.pipelines)
    for (const auto& q : p.parameters) ++entries, longest = std::max(longest, q.description.size());
  std::printf("[ info     ] WELCOME payload %zu bytes, %zu parameter entries, longest description %zu bytes\n",
              payload, entries, longest);
  EXPECT_LT(payload, 32768u);
}

TEST(ParameterMetadata, OneZeroClientGetsTheOneZeroPayloadAndWorks) {
  ServerProcess server;
  RawClient c(server.tcp_url());
  std::vector<uint8_t> hello = protocol::encode(protocol::Hello{0, "old-client", ""}, 1);
  hello[5] = 0;  // header version_minor: a 1.0 client
  c.send_bytes(hello);
  std::vector<uint8_t> header_bytes = read_exactly(c.fd(), protocol::kHeaderSize);
  ASSERT_EQ(header_bytes.size(), protocol::kHeaderSize);
  protocol::Header h;
  ASSERT_FALSE(protocol::decode_header(header_bytes, 1u << 20, h));
  EXPECT_EQ(h.type, protocol::MessageType::Welcome);
  EXPECT_EQ(h.version_minor, protocol::kVersionMinor);  // the server's own version
  const std::vector<uint8_t> payload = read_exactly(c.fd(), h.payload_length);
  // Read as a 1.0 receiver does (minor 0: nothing may follow the 1.0 fields),
  // the payload ends exactly after `pipelines`: no tables were sent.
  protocol::Header as_1_0 = h;
  as_1_0.version_minor = 0;
  protocol::Message m;
  auto err = protocol::decode_payload(as_1_0, payload, m);
  ASSERT_FALSE(err) << err->field << ": " << err->message;
  const auto& w = std::get<protocol::Welcome>(m);
  EXPECT_FALSE(w.has_parameters);
  EXPECT_NE(find(w, "svgf"), nullptr);

  // The 1.0 client goes on as before: a passthrough session and one frame.
  const protocol::OpenSession request = passthrough_session(8, 4);
  std::vector<uint8_t> open = protocol::encode(request, 2);
  open[5] = 0;
  c.send_bytes(open);
  c.read_as_minor(0);  // its SESSION carries no watch key (1.6)
  auto reply = c.receive();
  ASSERT_TRUE(reply);
  auto* s = std::get_if<protocol::Session>(&reply->message);
  ASSERT_NE(s, nullptr);
  auto frame = make_frame(s->session_id, 0, 8, 4, request.channels, 0.5f);
  std::vector<uint8_t> frame_bytes = protocol::encode(frame.frame, 3);
  frame_bytes[5] = 0;
  c.send_bytes(frame_bytes);
  for (;;) {  // skip heartbeat PINGs
    auto r = c.receive();
    ASSERT_TRUE(r);
    if (std::holds_alternative<protocol::Ping>(r->message)) continue;
    ASSERT_TRUE(std::holds_alternative<protocol::Result>(r->message));
    EXPECT_EQ(r->header.request_id, 3u);
    break;
  }
}

TEST(ParameterMetadata, DnPipelinesAndPingShowTheTables) {
  ServerProcess server;
  std::string out;
  ASSERT_EQ(run_command(std::string(DN_DN_PATH) + " pipelines --server " + server.tcp_url(), out), 0) << out;
  const std::string row = line_starting(out, "    atrous_iterations ");
  ASSERT_FALSE(row.empty()) << out;
  std::istringstream fields(row);
  std::string name, def, lo, hi, integer;
  fields >> name >> def >> lo >> hi >> integer;
  EXPECT_EQ(def, "4");
  EXPECT_EQ(lo + " " + hi, "[0, 8]");
  EXPECT_EQ(integer, "yes");
  EXPECT_NE(row.find("a-trous iterations"), std::string::npos) << row;
  EXPECT_NE(out.find("\naccumulate\n  requires  radiance,normal,depth,motion\n"), std::string::npos) << out;
  EXPECT_NE(line_starting(out, "    name ").find("default  range"), std::string::npos) << out;

  out.clear();
  EXPECT_EQ(run_command(std::string(DN_DN_PATH) + " pipelines --server " + server.tcp_url() + " --pipeline nope", out), 2);
  EXPECT_NE(out.find("offers no pipeline 'nope'; it offers: passthrough, accumulate, svgf, svgf-fb"),
            std::string::npos)
      << out;

  out.clear();
  ASSERT_EQ(run_command(std::string(DN_DN_PATH) + " ping --count 1 --server " + server.tcp_url(), out), 0) << out;
  EXPECT_NE(out.find("  parameters: alpha_min, max_history, depth_tolerance, normal_threshold\n"), std::string::npos)
      << out;
  EXPECT_NE(out.find("  parameters: none\n"), std::string::npos) << out;
}

TEST(ParameterMetadata, DnDenoiseMisspeltParameterFailsBeforeTheSession) {
  const fs::path dir = fs::temp_directory_path() / ("dn-params-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::string out;
  ASSERT_EQ(run_command(std::string(DN_DNSYNTH_PATH) + " --out " + dir.string() + "/in --frames 2 --width 32 --height 16",
                  out),
            0)
      << out;
  ServerProcess server;
  out.clear();
  const int rc = run_command(std::string(DN_DN_PATH) + " denoise --server " + server.tcp_url() +
                           " --pipeline accumulate --param alpha=0.1 --preset dnrender --input '" + dir.string() +
                           "/in/frame_%04d.exr' --start 0 --end 1",
                       out);
  fs::remove_all(dir);
  EXPECT_EQ(rc, 2) << "a misspelt --param is a bad command line\n" << out;
  EXPECT_NE(out.find("client error InvalidParameter at OPEN_SESSION.parameters[0].name: pipeline 'accumulate' has "
                     "no parameter 'alpha'; valid names: alpha_min, max_history, depth_tolerance, normal_threshold"),
            std::string::npos)
      << out;
  // Nothing reached the server: it never saw an OPEN_SESSION to refuse.
  EXPECT_EQ(server.log().find("INVALID_PARAMETER"), std::string::npos) << server.log();
}

}  // namespace
}  // namespace dn::test
