// dnserver --advertise-url (protocol 1.8, SESSION.watch_url): the owner and
// watchers of a session learn where watchers connect — behind a balancer, the
// port that reaches this backend — and `watch_command()` uses it; a 1.7 client
// gets the SESSION it knows; a malformed URL stops the server at start.
#include <gtest/gtest.h>

#include "dn/client/client.hpp"
#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

constexpr const char* kAdvertised = "tcp://balancer.example:7101";

client::Session open_passthrough(client::Connection& conn) {
  client::SessionDesc desc;
  desc.width = 16;
  desc.height = 8;
  desc.pipeline = "passthrough";
  desc.channel(protocol::ChannelId::Radiance);
  return conn.open_session(desc);
}

TEST(AdvertiseUrl, OwnerAndWatcherLearnWhereToWatch) {
  ServerProcess server({"--advertise-url", kAdvertised});
  client::Connection owner = client::Connection::connect(server.tcp_url(), {});
  client::Session session = open_passthrough(owner);
  EXPECT_EQ(session.watch_url(), kAdvertised);
  // The key travels in the environment, never on dn's command line.
  EXPECT_EQ(session.watch_command().rfind("DN_WATCH_KEY=" + session.watch_key() + " dn watch --server " +
                                              kAdvertised + " --session ",
                                          0),
            0u)
      << session.watch_command();
  EXPECT_EQ(session.watch_command().find("--key"), std::string::npos) << session.watch_command();

  RawClient watcher(server.tcp_url());
  watcher.hello();
  watcher.send(protocol::Attach{session.id(), session.watch_key()}, 2);
  auto r = watcher.receive();
  ASSERT_TRUE(r);
  auto* s = std::get_if<protocol::Session>(&r->message);
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->watch_url.value_or("<absent>"), kAdvertised);
}

TEST(AdvertiseUrl, WithoutItTheUrlIsEmptyAndTheCommandNamesThisConnection) {
  ServerProcess server;
  client::Connection owner = client::Connection::connect(server.tcp_url(), {});
  client::Session session = open_passthrough(owner);
  EXPECT_EQ(session.watch_url(), "");
  EXPECT_NE(session.watch_command().find(owner.endpoint()), std::string::npos) << session.watch_command();
}

TEST(AdvertiseUrl, A17ClientGetsTheSessionItKnows) {
  ServerProcess server({"--advertise-url", kAdvertised});
  RawClient old_client(server.tcp_url());
  std::vector<uint8_t> hello = protocol::encode(protocol::Hello{0, "v1.7", ""}, 1);
  hello[5] = protocol::kWatchUrlMinor - 1;
  old_client.send_bytes(hello);
  old_client.read_as_minor(protocol::kWatchUrlMinor - 1);  // a URL would be trailing bytes to it
  ASSERT_TRUE(old_client.receive());
  std::vector<uint8_t> open = protocol::encode(passthrough_session(16, 8), 3);
  open[5] = protocol::kWatchUrlMinor - 1;
  old_client.send_bytes(open);
  auto r = old_client.receive();
  ASSERT_TRUE(r);
  auto* s = std::get_if<protocol::Session>(&r->message);
  ASSERT_NE(s, nullptr) << "the SESSION did not decode as 1.7 reads it";
  EXPECT_TRUE(s->watch_key.has_value());
  EXPECT_FALSE(s->watch_url.has_value());
}

TEST(AdvertiseUrl, AMalformedUrlStopsTheServerNamingIt) {
  std::string output;
  const int status = run_dnserver({"--advertise-url", "http://nowhere", "--listen", "tcp://127.0.0.1:0"}, output);
  EXPECT_NE(status, 0);
  EXPECT_NE(output.find("--advertise-url"), std::string::npos) << output;
}

}  // namespace
}  // namespace dn::test
