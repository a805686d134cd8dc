#include "server/cache_dir.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "server/log.hpp"

namespace dn::server {

std::string default_cache_dir() {
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && xdg[0] == '/') return std::string(xdg) + "/dnserver";
  if (const char* home = std::getenv("HOME"); home && home[0] == '/') return std::string(home) + "/.cache/dnserver";
  return "";
}

std::string prepare_cache_dir(const std::string& dir) {
  if (dir.empty() || dir[0] != '/') return "cache directory '" + dir + "' is not an absolute path";
  // Create each missing component; existing parents are left as they are.
  for (size_t slash = dir.find('/', 1);; slash = dir.find('/', slash + 1)) {
    const std::string part = dir.substr(0, slash);
    if (::mkdir(part.c_str(), 0700) != 0 && errno != EEXIST)
      return "cannot create " + part + ": " + std::strerror(errno);
    if (slash == std::string::npos) break;
  }
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) return "cannot inspect " + dir + ": " + std::strerror(errno);
  if (S_ISLNK(st.st_mode)) return dir + " is a symbolic link";
  if (!S_ISDIR(st.st_mode)) return dir + " is not a directory";
  if (st.st_uid != ::geteuid())
    return dir + " belongs to uid " + std::to_string(st.st_uid) + ", not to this user (uid " +
           std::to_string(::geteuid()) + ")";
  if (st.st_mode & (S_IWGRP | S_IWOTH)) return dir + " is writable by group or others";
  return "";
}

std::string resolve_cache_dir(const ServerOptions& options) {
  if (!options.disk_cache) return "";
  const std::string dir = options.cache_dir_given ? options.cache_dir : default_cache_dir();
  if (dir.empty()) {
    log::warn("cache_dir.none", {{"reason", "neither XDG_CACHE_HOME nor HOME is set; pipelines cached in memory only"}});
    return "";
  }
  const std::string problem = prepare_cache_dir(dir);
  if (problem.empty()) return dir;
  if (options.cache_dir_given) throw std::runtime_error("--cache-dir: " + problem);
  log::warn("cache_dir.unusable", {{"dir", dir}, {"reason", problem}});
  return "";
}

}  // namespace dn::server
