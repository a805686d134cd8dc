// The fuzz seed corpus (tests/fuzz/corpus): one valid message of every type
// as a stream, the same as bare payloads (first byte = type - 1, see
// tests/fuzz/protocol_fuzz.cpp), one multi-message stream, and a WELCOME
// from a 1.0 server (no parameter tables). The files are
// committed; this test checks they are still what the encoder writes and
// rewrites them when DN_WRITE_FUZZ_CORPUS=1 is set.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "support.hpp"

namespace dn::protocol::test {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Fixed contents (no random distributions, whose output differs between
// standard libraries), each small and touching most fields.
std::vector<Message> seed_messages(const std::vector<uint8_t>& pixels) {
  const std::span<const uint8_t> px(pixels);
  Welcome welcome{"dnserver 0.1.0", "llvmpipe (LLVM 15.0.6, 256 bits)", {64u << 20, 1u << 30, 8, 4096, 4096, 4}, {}};
  welcome.pipelines = {{"svgf", 0x1C9, 0x200}, {"svgf-fb", 0x1F9, 0x200}};
  welcome.has_parameters = true;
  const std::vector<ParameterInfo> svgf_parameters = {
      {"alpha_colour", 0.05, 0.0, 1.0, false, "Floor of the temporal blend weight of the demodulated colour."},
      {"atrous_iterations", 4.0, 0.0, 8.0, true, "Number of a-trous iterations (steps 1, 2, 4, ...)."}};
  welcome.pipelines[0].parameters = svgf_parameters;
  welcome.pipelines[1].parameters = svgf_parameters;
  welcome.pipelines[1].parameters.push_back(
      {"specular_demodulated", 0.0, 0.0, 1.0, true, "1: the specular channel is already divided by F_beta."});
  Frame frame;
  frame.info.session_id = 1;
  frame.info.frame_index = 17;
  frame.info.flags = kFrameReset;
  frame.info.motion = MotionConvention::PixelsToNext;
  frame.info.view = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -5, 1};
  frame.info.projection = {1.5f, 0, 0, 0, 0, 2, 0, 0, 0, 0, -1, -1, 0, 0, -0.2f, 0};
  frame.info.prev_view = frame.info.view;
  frame.info.prev_projection = frame.info.projection;
  frame.info.jitter = {0.25f, -0.25f};
  frame.info.prev_jitter = {-0.125f, 0.375f};
  frame.planes = {{ChannelId::Radiance, Format::F16, px.first(12)},
                  {ChannelId::Depth, Format::F32, px.first(8)},
                  {ChannelId::Motion, Format::F16, px.first(8)}};
  Result result{1, 17, {{"reproject", 0.125}, {"atrous", 1.5}}, {{ChannelId::Output, Format::F16, px.first(12)}},
                SampleCounts{true, 3, 8}};
  return {
      Hello{0, "renderer", "secret-token"},
      welcome,
      Error{ErrorCode::InvalidChannel, "OPEN_SESSION.channels[1].format", "depth must be F32"},
      OpenSession{2, 1, "svgf", Format::F16, {{"alpha", 0.2}, {"iterations", 5}},
                  {{ChannelId::Radiance, Format::F16}, {ChannelId::Depth, Format::F32}, {ChannelId::Motion, Format::F16}}},
      Session{1, 2, 1, "svgf", Format::F16, 4096, false,
              {{ChannelId::Radiance, Format::F16}, {ChannelId::Depth, Format::F32}},
              "0123456789abcdef0123456789abcdef", "tcp://127.0.0.1:7101", "albedo, normal, depth and motion"},
      frame,
      result,
      Attach{1, "0123456789abcdef0123456789abcdef"},
      Ping{0x0123456789ABCDEFu},
      Pong{0x0123456789ABCDEFu},
      CloseSession{1},
      SessionClosed{1, 18},
      StatsRequest{},
      Stats{{{"sessions", 1}, {"frames", 18}, {"device_ms_p50", 2.5}}},
  };
}

std::vector<std::pair<std::string, std::vector<uint8_t>>> seeds() {
  std::vector<uint8_t> pixels(12);
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<uint8_t>(0x10 * i + 1);
  std::vector<std::pair<std::string, std::vector<uint8_t>>> out;
  std::vector<uint8_t> stream;
  uint64_t request_id = 1;
  for (const Message& m : seed_messages(pixels)) {
    const MessageType type = type_of(m);
    const auto bytes = encode(m, request_id++, type == MessageType::Frame ? kFlagNoOutput : 0);
    out.emplace_back(lower(to_string(type)) + ".msg", bytes);
    std::vector<uint8_t> payload_seed = {static_cast<uint8_t>(static_cast<uint16_t>(type) - 1)};
    payload_seed.insert(payload_seed.end(), bytes.begin() + kHeaderSize, bytes.end());
    out.emplace_back(lower(to_string(type)) + ".payload", payload_seed);
    stream.insert(stream.end(), bytes.begin(), bytes.end());
  }
  out.emplace_back("stream.msg", stream);
  // A 1.0 server's WELCOME: header minor 0, the payload ends after the pipelines.
  Welcome old = std::get<Welcome>(seed_messages(pixels)[1]);
  old.has_parameters = false;
  for (auto& p : old.pipelines) p.parameters.clear();
  std::vector<uint8_t> old_bytes = encode(old, 1, 0);
  old_bytes[5] = 0;
  out.emplace_back("welcome_1_0.msg", old_bytes);
  return out;
}

std::vector<uint8_t> read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(FuzzCorpus, SeedsAreCurrent) {
  const fs::path dir = DN_FUZZ_CORPUS_DIR;
  const auto all = seeds();
  if (const char* w = std::getenv("DN_WRITE_FUZZ_CORPUS"); w && std::string(w) == "1") {
    fs::create_directories(dir);
    for (const auto& [name, bytes] : all) {
      std::ofstream out(dir / name, std::ios::binary);
      out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    }
  }
  for (const auto& [name, bytes] : all) {
    ASSERT_TRUE(fs::exists(dir / name)) << name << " missing; run with DN_WRITE_FUZZ_CORPUS=1";
    EXPECT_EQ(read_file(dir / name), bytes) << name << " is stale; run with DN_WRITE_FUZZ_CORPUS=1";
  }
}

TEST(FuzzCorpus, StreamSeedsDecode) {
  const fs::path dir = DN_FUZZ_CORPUS_DIR;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() != ".msg") continue;
    const auto bytes = read_file(e.path());
    size_t pos = 0, count = 0;
    while (pos < bytes.size()) {
      Decoded d;
      std::vector<uint8_t> storage;
      auto err = decode_message(std::span(bytes).subspan(pos), kMaxMessage, d, storage);
      ASSERT_FALSE(err) << e.path() << ": " << err->field << ": " << err->message;
      pos += kHeaderSize + d.header.payload_length;
      ++count;
    }
    EXPECT_EQ(pos, bytes.size());
    EXPECT_GE(count, 1u);
  }
}

}  // namespace
}  // namespace dn::protocol::test
