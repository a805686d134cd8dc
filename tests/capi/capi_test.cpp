// Runs the C test program tests/capi/c_api_test.c against a real dnserver on
// loopback (TCP) and on its Unix socket; it must exit 0.
#include <gtest/gtest.h>

#include <string>

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

}  // namespace
}  // namespace dn::test
