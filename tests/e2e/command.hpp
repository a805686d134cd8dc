// Runs a shell command from an end-to-end test (the dn CLI, a compiled docs
// example), collecting what it prints.
#pragma once

#include <string>

namespace dn::test {

// Runs `command` with stdout and stderr captured into `output`; returns the
// exit status, -1 if it did not exit normally.
int run_command(const std::string& command, std::string& output);

}  // namespace dn::test
