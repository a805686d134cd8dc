// Runs the C test program tests/capi/c_api_test.c against a real dnserver on
// loopback (TCP) and on its Unix socket, and through a server restart; it
// must exit 0.
#include <gtest/gtest.h>
#include <signal.h>

#include <memory>
#include <string>

#include "child_process.hpp"
#include "command.hpp"
#include "server_process.hpp"

namespace dn::test {
namespace {

void run_c_api_test(const std::string& url) {
  std::string output;
  const int status = run_command("'" + std::string(DN_C_API_TEST_PATH) + "' '" + url + "'", output);
  EXPECT_EQ(status, 0) << "c_api_test " << url << ":\n" << output;
  EXPECT_NE(output.find(", 0 failed"), std::string::npos) << output;
}

TEST(CApi, CTestProgramAgainstARealServerOverTcp) {
  ServerProcess server;
  run_c_api_test(server.tcp_url());
}

TEST(CApi, CTestProgramAgainstARealServerOverAUnixSocket) {
  ServerProcess server;
  run_c_api_test(server.unix_url());
}

// The server is killed under a running program and started again on the same
// addresses: the program sees DN_ERROR_CONNECTION, reconnects with
// dnCommitDevice and goes on after dnCommitFilter (c_api_test.c, test_reconnect).
TEST(CApi, CommitDeviceReconnectsAfterTheServerRestarts) {
  auto server = std::make_unique<ServerProcess>();
  const std::string tcp = server->tcp_url(), unix_socket = server->unix_url();
  ChildProcess program(DN_C_API_TEST_PATH, {tcp, "reconnect"});
  ASSERT_TRUE(program.read_until("serving", 60.0)) << program.output();
  server->signal_and_wait(SIGKILL);
  server.reset();
  server = std::make_unique<ServerProcess>(std::vector<std::string>{"--listen", tcp, "--listen", unix_socket},
                                           /*add_listeners=*/false);
  EXPECT_EQ(program.wait(120.0), 0) << program.output();
  EXPECT_NE(program.output().find(", 0 failed"), std::string::npos) << program.output();
}

}  // namespace
}  // namespace dn::test
