// docs/client.md's C++ and C examples (extracted and compiled by
// doc_examples.cmake) run against a real dnserver on loopback: each must exit 0.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "command.hpp"
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

// The ```c blocks: C99 programs linked against the C API (dn::c).
constexpr DocExample kCExamples[] = {
#include "doc_examples_c.inc"
};

TEST(DocExamples, EveryCppExampleInClientMdRunsAgainstARealServer) {
  // The page has at least the renderer loop and the parameter example.
  ASSERT_GE(std::size(kExamples), 2u);
  ServerProcess server;
  for (const DocExample& e : kExamples) {
    std::string output;
    const int status = run_command("'" + std::string(e.path) + "' '" + server.tcp_url() + "'", output);
    EXPECT_EQ(status, 0) << "docs/client.md example at line " << e.line << " failed:\n" << output;
  }
}

TEST(DocExamples, EveryCExampleInClientMdRunsAgainstARealServer) {
  ASSERT_GE(std::size(kCExamples), 1u);  // the C API section's program
  ServerProcess server;
  for (const DocExample& e : kCExamples) {
    std::string output;
    const int status = run_command("'" + std::string(e.path) + "' '" + server.tcp_url() + "'", output);
    EXPECT_EQ(status, 0) << "docs/client.md C example at line " << e.line << " failed:\n" << output;
  }
}

}  // namespace
}  // namespace dn::test
