// docs/client.md's C++ examples (extracted and compiled by doc_examples.cmake)
// run against a real dnserver on loopback: each must exit 0.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "server_process.hpp"

namespace dn::test {
namespace {

struct DocExample {
  const char* path;
  int line;  // of its first code line in docs/client.md
};

constexpr DocExample kExamples[] = {
#include "doc_examples.inc"
};

// Runs `path url`, collecting stdout and stderr; returns the exit status (-1 if it did not exit).
int run(const std::string& path, const std::string& url, std::string& output) {
  const std::string command = "'" + path + "' '" + url + "' 2>&1";
  FILE* p = ::popen(command.c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) output.append(buf, n);
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(DocExamples, EveryCppExampleInClientMdRunsAgainstARealServer) {
  // The page has at least the renderer loop and the parameter example.
  ASSERT_GE(std::size(kExamples), 2u);
  ServerProcess server;
  for (const DocExample& e : kExamples) {
    std::string output;
    const int status = run(e.path, server.tcp_url(), output);
    EXPECT_EQ(status, 0) << "docs/client.md example at line " << e.line << " failed:\n" << output;
  }
}

}  // namespace
}  // namespace dn::test
