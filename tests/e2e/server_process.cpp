#include "server_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <thread>

namespace dn::test {
namespace {

using Clock = std::chrono::steady_clock;

pid_t spawn(const std::vector<std::string>& args, int& out_fd) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
  pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    ::dup2(fds[1], 2);
    ::dup2(fds[1], 1);
    std::vector<char*> argv;
    std::string path = dnserver_path();
    argv.push_back(path.data());
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(path.c_str(), argv.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  out_fd = fds[0];
  return pid;
}

// Reads what is available within timeout; returns false at EOF.
bool read_some(int fd, std::string& into, int timeout_ms) {
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return true;
  char buf[4096];
  ssize_t n = ::read(fd, buf, sizeof buf);
  if (n <= 0) return false;
  into.append(buf, static_cast<size_t>(n));
  return true;
}

std::string field_after(const std::string& log, size_t from, const std::string& key) {
  size_t k = log.find(key, from);
  if (k == std::string::npos) return {};
  size_t start = k + key.size();
  size_t end = log.find_first_of(" \n", start);
  return log.substr(start, end - start);
}

}  // namespace

std::string dnserver_path() { return DN_DNSERVER_PATH; }

ServerProcess::ServerProcess(std::vector<std::string> args, bool add_listeners) {
  // The start-up warm-up compiles every default pipeline on a thread of its
  // own; most tests do not need it and it only adds load, so they run without
  // (a test that wants it passes --warm-up, which comes later and wins).
  args.insert(args.begin(), "--no-warm-up");
  if (add_listeners) {
    socket_path_ = "/tmp/dn-test-" + std::to_string(::getpid()) + "-" +
                   std::to_string(Clock::now().time_since_epoch().count() % 1000000) + ".sock";
    args.insert(args.begin(), {"--listen", "tcp://127.0.0.1:0", "--listen", "unix://" + socket_path_});
  }
  pid_ = spawn(args, stderr_fd_);
  read_log_until("event=ready", 60.0);
  for (size_t pos = 0; (pos = log_.find("event=listen", pos)) != std::string::npos; ++pos) {
    std::string url = field_after(log_, pos, "url=");
    if (url.rfind("tcp://", 0) == 0 && tcp_url_.empty()) tcp_url_ = url;
    if (url.rfind("unix://", 0) == 0 && unix_url_.empty()) unix_url_ = url;
  }
}

ServerProcess::~ServerProcess() {
  if (running()) signal_and_wait(SIGKILL, 10.0);
  if (stderr_fd_ >= 0) ::close(stderr_fd_);
}

void ServerProcess::read_log_until(const std::string& needle, double timeout_s) {
  auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (log_.find(needle) == std::string::npos) {
    if (Clock::now() > deadline) throw std::runtime_error("dnserver did not log '" + needle + "':\n" + log_);
    if (!read_some(stderr_fd_, log_, 100)) throw std::runtime_error("dnserver exited early:\n" + log_);
  }
}

std::string ServerProcess::log() {
  for (;;) {
    pollfd p{stderr_fd_, POLLIN, 0};
    if (::poll(&p, 1, 0) <= 0 || !read_some(stderr_fd_, log_, 0)) break;
  }
  return log_;
}

bool ServerProcess::running() {
  if (exit_status_ >= 0 || pid_ <= 0) return false;
  int status;
  pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    exit_status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return false;
  }
  return true;
}

int ServerProcess::signal_and_wait(int sig, double timeout_s) {
  if (!running()) return exit_status_;
  ::kill(pid_, sig);
  auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (running()) {
    log();
    if (Clock::now() > deadline) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
      exit_status_ = 255;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  log();
  return exit_status_;
}

int run_dnserver(const std::vector<std::string>& args, std::string& output, double timeout_s) {
  int fd;
  pid_t pid = spawn(args, fd);
  auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
  while (read_some(fd, output, 100)) {
    if (Clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      break;
    }
  }
  ::close(fd);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace dn::test
