// dn preview's pieces without a browser: the --http address rules (loopback or
// a token), the binary frame and status messages the page decodes, and key files.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <cstring>
#include <limits>

#include "args.hpp"
#include "commands.hpp"
#include "preview/preview_address.hpp"
#include "preview/preview_frame.hpp"
#include "dn/client/watch_file.hpp"

namespace {

using namespace dn;
using dn::cli::parse_preview_address;
using dn::cli::UsageError;

TEST(PreviewAddress, LoopbackAndOtherAddresses) {
  const auto a = parse_preview_address("127.0.0.1:7879");
  EXPECT_EQ(a.host, "127.0.0.1");
  EXPECT_EQ(a.port, 7879);
  EXPECT_TRUE(a.loopback);
  EXPECT_EQ(a.civetweb_ports(), "127.0.0.1:7879");
  const auto l = parse_preview_address("localhost:0");
  EXPECT_EQ(l.host, "127.0.0.1");
  EXPECT_EQ(l.port, 0);
  EXPECT_TRUE(l.loopback);
  EXPECT_TRUE(parse_preview_address("127.8.9.10:1").loopback);
  const auto v6 = parse_preview_address("[::1]:80");
  EXPECT_TRUE(v6.ipv6 && v6.loopback);
  EXPECT_EQ(v6.civetweb_ports(), "[::1]:80");
  EXPECT_EQ(v6.url_host, "[::1]");
  EXPECT_FALSE(parse_preview_address("0.0.0.0:80").loopback);
  EXPECT_FALSE(parse_preview_address("192.168.1.2:80").loopback);
  EXPECT_FALSE(parse_preview_address("[::]:80").loopback);
}

TEST(PreviewAddress, RefusesWhatIsNotHostPort) {
  for (const char* bad : {"7879", ":80", "example.org:80", "127.0.0.1:70000", "127.0.0.1:-1", "127.0.0.1:x",
                          "[::1:80", "1.2.3:80"}) {
    try {
      parse_preview_address(bad);
      ADD_FAILURE() << bad << " accepted";
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("--http"), std::string::npos) << e.what();
    }
  }
}

TEST(PreviewCommand, OffLoopbackWithoutATokenIsABadCommandLine) {
  ::unsetenv("DN_PREVIEW_TOKEN");
  try {
    cli::run_preview({"--session", "5", "--key", "00112233445566778899aabbccddeeff", "--http", "0.0.0.0:7879"});
    ADD_FAILURE() << "served off loopback without a token";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--http-token"), std::string::npos) << e.what();
  }
}

// A 2x1 fp32 result: a zero pixel and an infinite one.
client::Result two_pixel_result(bool with_input) {
  static const float out[6] = {0.0f, 0.0f, 0.0f, std::numeric_limits<float>::infinity(), 1e30f, 0.5f};
  static const float in[6] = {std::numeric_limits<float>::quiet_NaN(), -1.0f, 0.0f, 0.0f, 0.0f, 0.0f};
  client::Result r;
  r.frame_index = 42;
  r.width = 2;
  r.height = 1;
  r.output = {reinterpret_cast<const uint8_t*>(out), sizeof out};
  if (with_input) r.input = {reinterpret_cast<const uint8_t*>(in), sizeof in};
  r.timings = {{"svgf_atrous", 1.5}, {"quote\" and\nnewline", 0.25}};
  return r;
}

TEST(PreviewFrame, HeaderIsJsonWithEscapedNames) {
  cli::PreviewContext ctx;
  ctx.session_id = 18446744073709551615ull;
  ctx.pipeline = "svgf";
  const std::string json = cli::preview_header_json(two_pixel_result(false), ctx);
  EXPECT_NE(json.find("\"session\":\"18446744073709551615\""), std::string::npos) << json;  // a string: > 2^53
  EXPECT_NE(json.find("\"frame_index\":42"), std::string::npos) << json;
  EXPECT_NE(json.find("\"pipeline\":\"svgf\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"name\":\"quote\\\" and\\u000anewline\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"total_ms\":1.7500"), std::string::npos) << json;
  EXPECT_NE(json.find("\"has_input\":false"), std::string::npos) << json;
  EXPECT_NE(json.find("\"samples\":null"), std::string::npos) << json;
  EXPECT_EQ(json.find('\n'), std::string::npos) << "a raw control character in the JSON";
  client::Result counted = two_pixel_result(false);
  counted.samples = protocol::SampleCounts{true, 3, 17};
  const std::string with_counts = cli::preview_header_json(counted, ctx);
  EXPECT_NE(with_counts.find("\"samples\":{\"min\":3,\"median\":17}"), std::string::npos) << with_counts;
}

TEST(PreviewFrame, MessageIsLengthJsonThenRgba8Planes) {
  cli::PreviewContext ctx;
  ctx.pipeline = "svgf";
  for (bool with_input : {false, true}) {
    const client::Result r = two_pixel_result(with_input);
    const std::vector<uint8_t> m = cli::encode_preview_frame(r, ctx);
    uint32_t n = 0;
    std::memcpy(&n, m.data(), 4);  // little-endian on every machine this runs on
    ASSERT_EQ(m.size(), 4 + n + 8 * (with_input ? 2 : 1));
    EXPECT_EQ(std::string(m.begin() + 4, m.begin() + 4 + n), cli::preview_header_json(r, ctx));
    const uint8_t* px = m.data() + 4 + n;
    // Output: black, then +Inf and 1e30 saturate to white, 0.5 through ACES and sRGB.
    const uint8_t expected_out[8] = {0, 0, 0, 255, 255, 255, px[6], 255};
    EXPECT_EQ(std::vector<uint8_t>(px, px + 8), std::vector<uint8_t>(expected_out, expected_out + 8));
    // ACES(0.5) = 0.6163 display-linear, sRGB-encoded 0.8073 -> 206.
    EXPECT_EQ(px[6], 206);
    if (with_input) {
      // NaN and negatives map to 0.
      const uint8_t expected_in[8] = {0, 0, 0, 255, 0, 0, 0, 255};
      EXPECT_EQ(std::vector<uint8_t>(px + 8, px + 16), std::vector<uint8_t>(expected_in, expected_in + 8));
    }
  }
}

TEST(PreviewFrame, StatusIsLengthThenJsonAlone) {
  const std::vector<uint8_t> m =
      cli::encode_preview_status("ended", 18446744073709551615ull, "session \"x\" ended after 3 frames");
  const std::string json =
      R"({"status":"ended","session":"18446744073709551615","detail":"session \"x\" ended after 3 frames"})";
  ASSERT_EQ(m.size(), 4 + json.size());
  uint32_t n = 0;
  std::memcpy(&n, m.data(), 4);
  EXPECT_EQ(n, json.size());
  EXPECT_EQ(std::string(m.begin() + 4, m.end()), json);
}

// A key file round-trips, is written 0600 over an older one, and is refused once others may read it.
TEST(WatchFile, WrittenPrivateReadBackRefusedWhenOpen) {
  const std::string path = ::testing::TempDir() + "dn_watch_file_" + std::to_string(::getpid());
  const std::string key = "00112233445566778899aabbccddeeff";
  {
    std::ofstream(path) << "stale\n";
  }
  ::chmod(path.c_str(), 0644);
  client::write_watch_file(path, {key, 18446744073709551615ull});
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  const client::WatchFile f = client::read_watch_file(path);
  EXPECT_EQ(f.key, key);
  EXPECT_EQ(f.session_id, 18446744073709551615ull);
  ::chmod(path.c_str(), 0604);
  try {
    client::read_watch_file(path);
    ADD_FAILURE() << "read a key file other users can read";
  } catch (const client::Error& e) {
    EXPECT_NE(std::string(e.what()).find("(mode 0604)"), std::string::npos) << e.what();
  }
  ::unlink(path.c_str());
}

}  // namespace
