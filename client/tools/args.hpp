// A small command-line parser for the dn tool: "--name value", "--name=value",
// boolean flags, repeatable options, aliases ("-r", "--alb") and, for a
// command that takes them, positional arguments.
#pragma once

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace dn::cli {

// Bad command line: printed as "dn <cmd>: <message>" and exit status 2 (kExitUsage).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Args {
 public:
  struct Spec {
    std::string name;        // long name without "--"
    std::string alias;       // short alias "-r" or long alias "--alb"; may be empty
    bool takes_value = true;
    bool repeatable = false;
    std::string help;        // one line, printed by usage()
    std::string metavar = "VALUE";
  };

  Args(std::string command, std::vector<Spec> specs) : command_(std::move(command)), specs_(std::move(specs)) {}
  // A command that takes up to `max` positional arguments, named `metavar` in messages.
  Args(std::string command, std::vector<Spec> specs, std::string metavar, size_t max)
      : command_(std::move(command)), specs_(std::move(specs)), positional_metavar_(std::move(metavar)),
        max_positionals_(max) {}

  // Throws UsageError on unknown options, missing values, repeated
  // non-repeatable options and positional arguments beyond the command's.
  void parse(const std::vector<std::string>& argv);

  const std::vector<std::string>& positionals() const { return positionals_; }

  bool has(const std::string& name) const { return values_.count(name) != 0; }
  std::optional<std::string> get(const std::string& name) const;
  std::string get_or(const std::string& name, const std::string& fallback) const;
  std::string require(const std::string& name) const;  // UsageError if absent
  std::vector<std::string> all(const std::string& name) const;
  long long get_int(const std::string& name, long long fallback, long long min, long long max) const;
  double get_double(const std::string& name, double fallback) const;
  // UsageError unless min <= value <= max.
  double get_double(const std::string& name, double fallback, double min, double max) const;

  std::string usage() const;  // option list

 private:
  const Spec* find(const std::string& name) const;
  std::string command_;
  std::vector<Spec> specs_;
  std::map<std::string, std::vector<std::string>> values_;
  std::string positional_metavar_;
  size_t max_positionals_ = 0;
  std::vector<std::string> positionals_;
};

long long parse_int(const std::string& text, const std::string& what);
// A finite number; UsageError naming `what` otherwise (also for "nan", "inf").
double parse_double(const std::string& text, const std::string& what);
// "name=value" -> {name, value}; UsageError naming `what` otherwise.
std::pair<std::string, std::string> split_assignment(const std::string& text, const std::string& what);

}  // namespace dn::cli
