// A child process whose stdout and stderr the test reads line by line as they
// come (e.g. dnrender --server), so a test can act when a line appears
// instead of sleeping.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace dn::test {

class ChildProcess {
 public:
  // Runs `path` with `args`, stdout and stderr into one pipe.
  ChildProcess(const std::string& path, const std::vector<std::string>& args);
  ~ChildProcess();  // kills it if still running
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // The next whole line (without '\n'), or nullopt at EOF or after timeout_s.
  std::optional<std::string> read_line(double timeout_s);
  // Reads lines until one contains `needle`; returns it, or nullopt at EOF or timeout.
  std::optional<std::string> read_until(const std::string& needle, double timeout_s);
  // Everything read so far.
  const std::string& output() const { return output_; }
  bool running();
  // Reads to EOF (within timeout_s) and waits for the exit; the exit status, 128+signal, or -1 on timeout.
  int wait(double timeout_s);
  int pid() const { return pid_; }

 private:
  int pid_ = -1;
  int fd_ = -1;
  int status_ = -1;
  std::string output_;
  std::string partial_;
  bool eof_ = false;
};

}  // namespace dn::test
