// Sessions as capabilities against a real dnserver (docs/server.md,
// "Security"): ATTACH needs the session's watch key and is refused exactly
// like an unknown id without it; STATS names a session only to its owner or
// to an administrator; a configured token is required on every listener; and
// another local uid, connected over loopback TCP, sees no session and can
// watch one only with its key.
#include <grp.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "raw_client.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

using protocol::ErrorCode;

constexpr uid_t kNobody = 65534;  // an unprivileged uid that owns nothing

std::string write_token_file(const std::string& token) {
  std::string path = "/tmp/dn-security-token-" + std::to_string(::getpid());
  std::ofstream(path) << token << "\n";
  return path;
}

// STATS names that identify a session: any per-session entry, or one that
// carries the id itself.
std::vector<std::string> session_names(const std::vector<protocol::StatValue>& values, uint64_t id) {
  std::vector<std::string> out;
  for (const auto& v : values)
    if (v.name.rfind("session.", 0) == 0 || v.name.find(std::to_string(id)) != std::string::npos)
      out.push_back(v.name);
  return out;
}

double value_of(const std::vector<protocol::StatValue>& values, const std::string& name) {
  for (const auto& v : values)
    if (v.name == name) return v.value;
  return -1.0;
}

// The ERROR an ATTACH gets, or a description of what came instead.
protocol::Error attach_refusal(RawClient& c, uint64_t session_id, std::string key, uint64_t request_id) {
  c.send(protocol::Attach{session_id, std::move(key)}, request_id);
  auto r = c.receive();
  if (!r) return {ErrorCode::Internal, "", "no reply"};
  if (auto* e = std::get_if<protocol::Error>(&r->message)) return *e;
  return {ErrorCode::Internal, "", std::string("not refused: ") + protocol::to_string(r->header.type)};
}

// The message with the session id in it replaced, so refusals of different ids compare.
std::string without_id(std::string message, uint64_t id) {
  const std::string digits = std::to_string(id);
  if (auto at = message.find(digits); at != std::string::npos) message.replace(at, digits.size(), "<id>");
  return message;
}

// The same key with its first hex digit changed: well-formed, and wrong.
std::string other_key(std::string key) {
  key[0] = key[0] == '0' ? '1' : '0';
  return key;
}

TEST(Security, EverySessionGetsItsOwnRandomWatchKey) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  const protocol::Session a = owner.open_session(passthrough_session(16, 8), 1);
  const protocol::Session b = owner.open_session(passthrough_session(16, 8), 2);
  for (const protocol::Session* s : {&a, &b}) {
    ASSERT_TRUE(s->watch_key.has_value()) << "a 1.6 client's SESSION has no watch_key";
    ASSERT_EQ(s->watch_key->size(), 32u) << *s->watch_key;
    EXPECT_EQ(s->watch_key->find_first_not_of("0123456789abcdef"), std::string::npos) << *s->watch_key;
  }
  EXPECT_NE(*a.watch_key, *b.watch_key);
}

TEST(Security, AttachWithoutTheKeyIsRefusedLikeAnUnknownSession) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  const auto request = passthrough_session(32, 16);
  const protocol::Session opened = owner.open_session(request);
  const uint64_t sid = opened.session_id;
  const std::string key = opened.watch_key.value_or("");
  ASSERT_EQ(key.size(), 32u);

  RawClient watcher(server.tcp_url());
  watcher.hello();
  const uint64_t unknown = sid + 1;
  const protocol::Error no_session = attach_refusal(watcher, unknown, key, 2);
  const protocol::Error no_key = attach_refusal(watcher, sid, "", 3);
  const protocol::Error wrong_key = attach_refusal(watcher, sid, other_key(key), 4);
  EXPECT_EQ(no_session.code, ErrorCode::UnknownSession) << no_session.message;
  EXPECT_EQ(no_session.field, "ATTACH.session_id");
  EXPECT_EQ(no_session.message, "no open session " + std::to_string(unknown) + " with that watch key");
  for (const protocol::Error* e : {&no_key, &wrong_key}) {
    EXPECT_EQ(e->code, no_session.code) << e->message;
    EXPECT_EQ(e->field, no_session.field);
    EXPECT_EQ(without_id(e->message, sid), without_id(no_session.message, unknown));
  }

  // A refused ATTACH attached nothing: a connection refused twice gets no frame.
  RawClient refused(server.tcp_url());
  refused.hello();
  attach_refusal(refused, sid, other_key(key), 5);

  // With the key: the read-only SESSION (which does not repeat the key), then the owner's frames.
  watcher.send(protocol::Attach{sid, key}, 6);
  auto ack = watcher.receive();
  ASSERT_TRUE(ack);
  auto* s = std::get_if<protocol::Session>(&ack->message);
  ASSERT_NE(s, nullptr) << "ATTACH with the key was not answered with SESSION";
  EXPECT_TRUE(s->read_only);
  EXPECT_EQ(s->session_id, sid);
  EXPECT_EQ(s->watch_key, std::optional<std::string>(""));

  auto f = make_frame(sid, 0, 32, 16, request.channels, 3.0f);
  owner.send(f.frame, 7);
  ASSERT_TRUE(owner.receive());
  auto seen = watcher.receive();
  ASSERT_TRUE(seen);
  auto* result = std::get_if<protocol::Result>(&seen->message);
  ASSERT_NE(result, nullptr);
  EXPECT_EQ(first_output_value(*result), 3.0f);
  // The RESULT went out to every watcher together; had `refused` been attached, its copy
  // would be ahead of the PONG.
  refused.send(protocol::Ping{77}, 8);
  auto pong = refused.receive();
  ASSERT_TRUE(pong);
  EXPECT_NE(std::get_if<protocol::Pong>(&pong->message), nullptr)
      << "a refused connection got " << protocol::to_string(pong->header.type);
}

TEST(Security, OlderClientsAttachIsRefusedNamingTheVersion) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  const protocol::Session opened = owner.open_session(passthrough_session(16, 8));

  RawClient old_client(server.tcp_url());
  std::vector<uint8_t> hello = protocol::encode(protocol::Hello{0, "v1.5", ""}, 1);
  hello[5] = 5;  // header version_minor: a 1.5 client, which knows no watch key
  old_client.send_bytes(hello);
  old_client.read_as_minor(5);  // a key in what the server sends it would be trailing bytes
  ASSERT_TRUE(old_client.receive());
  // Its own sessions open as before, without a key (so no one can watch them).
  std::vector<uint8_t> open = protocol::encode(passthrough_session(16, 8), 3);
  open[5] = 5;
  old_client.send_bytes(open);
  auto own = old_client.receive();
  ASSERT_TRUE(own);
  ASSERT_NE(std::get_if<protocol::Session>(&own->message), nullptr);
  EXPECT_FALSE(std::get<protocol::Session>(own->message).watch_key.has_value());

  std::vector<uint8_t> attach = protocol::encode(protocol::Attach{opened.session_id, std::nullopt}, 2);
  attach[5] = 5;
  old_client.send_bytes(attach);
  auto r = old_client.receive();
  ASSERT_TRUE(r);
  auto* e = std::get_if<protocol::Error>(&r->message);
  ASSERT_NE(e, nullptr) << "a 1.5 client attached without a key";
  EXPECT_EQ(e->code, ErrorCode::UnknownSession);
  EXPECT_EQ(e->field, "ATTACH.watch_key");
  EXPECT_NE(e->message.find("protocol 1.6"), std::string::npos) << e->message;
  EXPECT_NE(e->message.find("speaks 1.5"), std::string::npos) << e->message;
}

TEST(Security, StatsNameASessionOnlyToItsOwner) {
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  const uint64_t sid = owner.open(passthrough_session(16, 8));
  RawClient other(server.tcp_url());
  other.hello();

  const auto mine = stats_values(owner);
  EXPECT_EQ(value_of(mine, "session." + std::to_string(sid) + ".frames"), 0.0);
  const auto theirs = stats_values(other);
  EXPECT_EQ(session_names(theirs, sid), std::vector<std::string>{});
  EXPECT_EQ(value_of(theirs, "sessions"), 1.0) << "the aggregate count stays visible";
}

TEST(Security, AdministratorWithTheTokenSeesEverySession) {
  const std::string file = write_token_file("admin-token");
  ServerProcess server({"--token-file", file});
  RawClient owner(server.tcp_url());
  owner.hello("admin-token");
  const uint64_t sid = owner.open(passthrough_session(16, 8));
  RawClient admin(server.unix_url());
  admin.hello("admin-token");
  EXPECT_EQ(value_of(stats_values(admin), "session." + std::to_string(sid) + ".frames"), 0.0);
  ::unlink(file.c_str());
}

TEST(Security, ConfiguredTokenIsRequiredOnLoopbackAndTheUnixSocket) {
  const std::string file = write_token_file("local-token");
  ServerProcess server({"--token-file", file});
  for (const std::string& url : {server.tcp_url(), server.unix_url()}) {
    SCOPED_TRACE(url);
    RawClient c(url);
    c.send(protocol::Hello{0, "no-token", ""}, 1);
    auto r = c.receive();
    ASSERT_TRUE(r);
    auto* e = std::get_if<protocol::Error>(&r->message);
    ASSERT_NE(e, nullptr) << "a connection without the token was welcomed";
    EXPECT_EQ(e->code, ErrorCode::Unauthenticated);
    EXPECT_EQ(e->field, "HELLO.auth_token");
    EXPECT_TRUE(c.closed_by_server());
  }
  ::unlink(file.c_str());
}

// What another uid's client saw, one `name=value` line each.
std::map<std::string, std::string> parse_report(const std::string& text) {
  std::map<std::string, std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (auto eq = line.find('='); eq != std::string::npos) out[line.substr(0, eq)] = line.substr(eq + 1);
  return out;
}

// In a child running as `uid` over loopback TCP: STATS, ATTACH without the
// key, with a wrong one, then with the key; after the last it writes one byte
// to `attached_fd` and waits for a frame.
std::string watch_as_other_user(const std::string& url, uid_t uid, uint64_t sid, const std::string& key,
                                int attached_fd) {
  std::ostringstream report;
  if (::setgroups(0, nullptr) != 0 || ::setgid(uid) != 0 || ::setuid(uid) != 0) return "error=setuid failed\n";
  report << "uid=" << ::getuid() << "\n";
  try {
    RawClient c(url);
    c.hello();
    const auto values = stats_values(c);
    report << "session_names=" << session_names(values, sid).size() << "\n";
    report << "sessions=" << value_of(values, "sessions") << "\n";
    const protocol::Error no_key = attach_refusal(c, sid, "", 2);
    report << "no_key=" << static_cast<int>(no_key.code) << " " << no_key.field << " " << without_id(no_key.message, sid)
           << "\n";
    const protocol::Error wrong = attach_refusal(c, sid, other_key(key), 3);
    report << "wrong_key=" << static_cast<int>(wrong.code) << " " << wrong.field << " " << without_id(wrong.message, sid)
           << "\n";
    c.send(protocol::Attach{sid, key}, 4);
    auto ack = c.receive();
    const bool attached = ack && std::get_if<protocol::Session>(&ack->message);
    report << "attached=" << attached << "\n";
    [[maybe_unused]] auto w = ::write(attached_fd, "A", 1);
    if (attached) {
      auto r = c.receive();
      if (r && std::get_if<protocol::Result>(&r->message))
        report << "frame_value=" << first_output_value(std::get<protocol::Result>(r->message)) << "\n";
    }
  } catch (const std::exception& e) {
    report << "error=" << e.what() << "\n";
  }
  return report.str();
}

TEST(Security, AnotherUidOnLoopbackSeesNoSessionAndWatchesOnlyWithTheKey) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to run the second client as uid " << kNobody;
  ServerProcess server;
  RawClient owner(server.tcp_url());
  owner.hello();
  const auto request = passthrough_session(16, 8);
  const protocol::Session opened = owner.open_session(request);
  const uint64_t sid = opened.session_id;

  int report_pipe[2], attached_pipe[2];
  ASSERT_EQ(::pipe(report_pipe), 0);
  ASSERT_EQ(::pipe(attached_pipe), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::close(report_pipe[0]);
    ::close(attached_pipe[0]);
    const std::string report =
        watch_as_other_user(server.tcp_url(), kNobody, sid, opened.watch_key.value_or(""), attached_pipe[1]);
    [[maybe_unused]] auto w = ::write(report_pipe[1], report.data(), report.size());
    ::_exit(0);
  }
  ::close(report_pipe[1]);
  ::close(attached_pipe[1]);
  // Once the child is attached (or gave up: EOF), the owner sends the frame it waits for.
  char byte;
  if (::read(attached_pipe[0], &byte, 1) == 1) {
    auto f = make_frame(sid, 0, 16, 8, request.channels, 5.0f);
    owner.send(f.frame, 1);
    ASSERT_TRUE(owner.receive());
  }
  std::string text;
  char buf[512];
  for (ssize_t n; (n = ::read(report_pipe[0], buf, sizeof buf)) > 0;) text.append(buf, static_cast<size_t>(n));
  ::close(report_pipe[0]);
  ::close(attached_pipe[0]);
  ::waitpid(pid, nullptr, 0);

  const auto report = parse_report(text);
  const auto seen = [&](const std::string& name) {
    auto it = report.find(name);
    return it == report.end() ? std::string("(missing)") : it->second;
  };
  SCOPED_TRACE(text);
  EXPECT_EQ(seen("error"), "(missing)");
  EXPECT_EQ(seen("uid"), std::to_string(kNobody));
  EXPECT_EQ(seen("session_names"), "0") << "another uid saw the session's id in STATS";
  EXPECT_EQ(seen("sessions"), "1");
  const std::string refusal = std::to_string(static_cast<int>(ErrorCode::UnknownSession)) +
                              " ATTACH.session_id no open session <id> with that watch key";
  EXPECT_EQ(seen("no_key"), refusal);
  EXPECT_EQ(seen("wrong_key"), refusal);
  EXPECT_EQ(seen("attached"), "1");
  EXPECT_EQ(seen("frame_value"), "5");
}

}  // namespace
}  // namespace dn::test
