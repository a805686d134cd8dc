#include "dn/client/watch_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>

#include "dn/client/error.hpp"
#include "dn/client/session.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::client {

namespace {

std::string mode_text(mode_t mode) {
  char text[8];
  std::snprintf(text, sizeof text, "%04o", unsigned(mode & 07777));
  return text;
}

std::string shell_quoted(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./:+=@,") ==
                        std::string::npos)
    return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string target(const Session& session, const std::string& watch_file) {
  if (!watch_file.empty()) return " --server " + session.watch_server() + " --key-file " + shell_quoted(watch_file);
  return " --server " + session.watch_server() + " --session " + std::to_string(session.id());
}

std::string key_prefix(const Session& session, const std::string& watch_file) {
  return watch_file.empty() && !session.watch_key().empty() ? "DN_WATCH_KEY=" + session.watch_key() + " " : "";
}

}  // namespace

WatchFile read_watch_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw Error::usage("watch key file " + path + ": " + std::strerror(errno));
  struct stat st {};
  const bool stat_ok = ::fstat(fd, &st) == 0;
  std::string text;
  char buffer[512];
  for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0 && text.size() < 4096;) text.append(buffer, size_t(n));
  ::close(fd);
  if (!stat_ok || !S_ISREG(st.st_mode)) throw Error::usage("watch key file " + path + " is not a regular file");
  if (st.st_mode & (S_IRWXG | S_IRWXO))
    throw Error::usage("watch key file " + path + " is readable or writable by other users (mode " +
                       mode_text(st.st_mode) + "): the key is a secret; chmod 600 " + path);
  std::istringstream lines(text);
  WatchFile file;
  std::getline(lines, file.key);
  if (!protocol::is_well_formed_watch_key(file.key) || file.key.empty())
    throw Error::usage("watch key file " + path + ": the first line is not a watch key (" +
                       std::to_string(protocol::kWatchKeyLength) + " lowercase hex digits)");
  std::string line;
  while (std::getline(lines, line)) {
    if (line.empty()) continue;
    const std::string word = "session ";
    const char* b = line.data() + word.size();
    const char* e = line.data() + line.size();
    if (line.rfind(word, 0) != 0 || std::from_chars(b, e, file.session_id).ptr != e || file.session_id == 0)
      throw Error::usage("watch key file " + path + ": expected 'session ID' after the key, got '" + line + "'");
  }
  return file;
}

void write_watch_file(const std::string& path, const WatchFile& file) {
  const std::string temporary = path + ".tmp" + std::to_string(::getpid());
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) throw Error::usage("cannot write watch key file " + path + ": " + std::strerror(errno));
  std::string text = file.key + "\n";
  if (file.session_id) text += "session " + std::to_string(file.session_id) + "\n";
  const bool written = ::fchmod(fd, 0600) == 0 && ::write(fd, text.data(), text.size()) == ssize_t(text.size());
  const int saved = errno;
  ::close(fd);
  if (!written || ::rename(temporary.c_str(), path.c_str()) != 0) {
    const int err = written ? errno : saved;
    ::unlink(temporary.c_str());
    throw Error::usage("cannot write watch key file " + path + ": " + std::strerror(err));
  }
}

std::string watch_hint(const Session& session, const std::string& watch_file) {
  return key_prefix(session, watch_file) + "dn watch" + target(session, watch_file);
}

std::string preview_hint(const Session& session, const std::string& watch_file) {
  return key_prefix(session, watch_file) + "dn preview" + target(session, watch_file);
}

std::string owner_hints(const std::string& program, const Session& session, const std::string& watch_file) {
  return program + ": session " + std::to_string(session.id()) + " (watch it with: " + watch_hint(session, watch_file) +
         " --output 'watch/%04d.png')\n" + program + ": preview it with: " + preview_hint(session, watch_file) +
         " (then open " + kDefaultPreviewUrl + ")\n";
}

}  // namespace dn::client
