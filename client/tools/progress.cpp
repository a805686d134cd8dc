#include "progress.hpp"

#include <unistd.h>

#include <cmath>

namespace dn::cli {

Progress::Progress(size_t total, bool tty, bool quiet, std::FILE* out)
    : total_(total), tty_(tty), quiet_(quiet), out_(out), start_(std::chrono::steady_clock::now()) {}

Progress::~Progress() { finish(); }

bool Progress::stderr_is_tty() { return ::isatty(STDERR_FILENO) == 1; }

void Progress::draw(const std::string& status) {
  constexpr int kWidth = 24;
  const double frac = total_ ? double(done_) / double(total_) : 1.0;
  const int filled = int(std::lround(frac * kWidth));
  std::string bar(size_t(filled), '#');
  bar.resize(kWidth, '.');
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::string eta;
  if (done_ > 0 && done_ < total_) {
    const double left = elapsed / double(done_) * double(total_ - done_);
    eta = "  ETA " + std::to_string(int(std::ceil(left))) + "s";
  }
  std::fprintf(out_, "\r\033[K[%s] %zu/%zu  %s%s", bar.c_str(), done_, total_, status.c_str(), eta.c_str());
  std::fflush(out_);
  drawn_ = true;
}

void Progress::frame_done(const std::string& line, const std::string& status) {
  ++done_;
  if (quiet_) return;
  if (tty_) {
    last_status_ = status;
    draw(status);
  } else {
    std::fprintf(out_, "%s\n", line.c_str());
    std::fflush(out_);
  }
}

void Progress::message(const std::string& line) {
  if (tty_ && drawn_) std::fprintf(out_, "\r\033[K");
  std::fprintf(out_, "%s\n", line.c_str());
  if (tty_ && drawn_) draw(last_status_);
  std::fflush(out_);
}

void Progress::finish() {
  if (tty_ && drawn_) {
    std::fprintf(out_, "\r\033[K");
    std::fflush(out_);
    drawn_ = false;
  }
}

std::string samples_status(const std::optional<protocol::SampleCounts>& samples) {
  if (!samples) return {};
  return "  samples min " + std::to_string(samples->min) + " median " + std::to_string(samples->median);
}

}  // namespace dn::cli
