// Starts a real dnserver process for end-to-end tests and finds its ports
// from the structured log it writes on stderr.
#pragma once

#include <string>
#include <vector>

namespace dn::test {

class ServerProcess {
 public:
  // Starts dnserver with `args` plus a loopback TCP listener on a free port
  // and a Unix socket; waits until it logs event=ready.
  explicit ServerProcess(std::vector<std::string> args = {}, bool add_listeners = true);
  ~ServerProcess();
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  const std::string& tcp_url() const { return tcp_url_; }
  const std::string& unix_url() const { return unix_url_; }
  int pid() const { return pid_; }
  bool running();
  // Sends a signal and waits for the exit; returns the exit status (or 128+signal).
  int signal_and_wait(int signal, double timeout_s = 30.0);
  // Everything the server wrote to stderr so far.
  std::string log();

 private:
  void read_log_until(const std::string& needle, double timeout_s);
  int pid_ = -1;
  int stderr_fd_ = -1;
  std::string log_;
  std::string tcp_url_, unix_url_, socket_path_;
  int exit_status_ = -1;
};

// Path of the dnserver binary under test (set by CMake).
std::string dnserver_path();

// Runs dnserver with args to completion; returns exit status and fills output with stdout+stderr.
int run_dnserver(const std::vector<std::string>& args, std::string& output, double timeout_s = 30.0);

}  // namespace dn::test
