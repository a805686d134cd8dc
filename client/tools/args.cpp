#include "args.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace dn::cli {

long long parse_int(const std::string& text, const std::string& what) {
  if (text.empty()) throw UsageError(what + ": expected an integer, got nothing");
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno != 0 || end != text.c_str() + text.size())
    throw UsageError(what + ": expected an integer, got '" + text + "'");
  return v;
}

double parse_double(const std::string& text, const std::string& what) {
  if (text.empty()) throw UsageError(what + ": expected a number, got nothing");
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (errno != 0 || end != text.c_str() + text.size() || !std::isfinite(v))
    throw UsageError(what + ": expected a finite number, got '" + text + "'");
  return v;
}

std::pair<std::string, std::string> split_assignment(const std::string& text, const std::string& what) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw UsageError(what + ": expected NAME=VALUE, got '" + text + "'");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

const Args::Spec* Args::find(const std::string& name) const {
  for (const auto& s : specs_)
    if (s.name == name || s.alias == "--" + name) return &s;
  return nullptr;
}

void Args::parse(const std::vector<std::string>& argv) {
  for (size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    const Spec* spec = nullptr;
    std::optional<std::string> inline_value;
    if (a.rfind("--", 0) == 0 && a.size() > 2) {
      std::string name = a.substr(2);
      if (auto eq = name.find('='); eq != std::string::npos) {
        inline_value = name.substr(eq + 1);
        name = name.substr(0, eq);
      }
      spec = find(name);
      if (!spec) throw UsageError("unknown option '--" + name + "' (see 'dn " + command_ + " --help')");
    } else if (a.size() > 1 && a[0] == '-' && a[1] != '-') {
      for (const auto& s : specs_)
        if (!s.alias.empty() && s.alias == a) spec = &s;
      if (!spec) throw UsageError("unknown option '" + a + "' (see 'dn " + command_ + " --help')");
    } else if (positionals_.size() < max_positionals_) {
      positionals_.push_back(a);
      continue;
    } else if (max_positionals_ > 0) {
      throw UsageError("unexpected argument '" + a + "': dn " + command_ + " takes " +
                       (max_positionals_ == 1 ? "one " : std::to_string(max_positionals_) + " ") + positional_metavar_ +
                       " and has '" + positionals_.back() + "' already (options take the form --name VALUE)");
    } else {
      throw UsageError("unexpected argument '" + a + "' (options take the form --name VALUE)");
    }
    std::string value;
    if (spec->takes_value) {
      if (inline_value) {
        value = *inline_value;
      } else {
        if (i + 1 >= argv.size()) throw UsageError("option --" + spec->name + " needs a value");
        value = argv[++i];
      }
    } else if (inline_value) {
      throw UsageError("option --" + spec->name + " takes no value");
    }
    auto& slot = values_[spec->name];
    if (!slot.empty() && !spec->repeatable) throw UsageError("option --" + spec->name + " given more than once");
    slot.push_back(value);
  }
}

std::optional<std::string> Args::get(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end() || it->second.empty()) return std::nullopt;
  return it->second.back();
}

std::string Args::get_or(const std::string& name, const std::string& fallback) const {
  auto v = get(name);
  return v ? *v : fallback;
}

std::string Args::require(const std::string& name) const {
  auto v = get(name);
  if (!v) throw UsageError("missing required option --" + name);
  return *v;
}

std::vector<std::string> Args::all(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

long long Args::get_int(const std::string& name, long long fallback, long long min, long long max) const {
  auto v = get(name);
  if (!v) return fallback;
  const long long x = parse_int(*v, "--" + name);
  if (x < min || x > max)
    throw UsageError("--" + name + " " + *v + " is out of range " + std::to_string(min) + ".." + std::to_string(max));
  return x;
}

double Args::get_double(const std::string& name, double fallback) const {
  auto v = get(name);
  return v ? parse_double(*v, "--" + name) : fallback;
}

double Args::get_double(const std::string& name, double fallback, double min, double max) const {
  const double x = get_double(name, fallback);
  if (has(name) && (x < min || x > max)) {
    char range[96];
    std::snprintf(range, sizeof range, "%g..%g", min, max);
    throw UsageError("--" + name + " " + *get(name) + " is out of range " + range);
  }
  return x;
}

std::string Args::usage() const {
  std::string out;
  for (const auto& s : specs_) {
    std::string left = "  ";
    if (!s.alias.empty()) left += s.alias + ", ";
    left += "--" + s.name;
    if (s.takes_value) left += " " + s.metavar;
    if (left.size() < 34) left.resize(34, ' ');
    else left += "  ";
    out += left + s.help + (s.repeatable ? " (repeatable)" : "") + "\n";
  }
  return out;
}

}  // namespace dn::cli
