#include "server_info.hpp"

#include <algorithm>
#include <cstdio>
#include <optional>
#include <vector>

#include "commands.hpp"
#include "dn/client/parameters.hpp"

namespace dn::cli {
namespace {

std::string pad(std::string s, size_t width) {
  if (s.size() < width) s.resize(width, ' ');
  return s;
}

// The parameter table of one pipeline, columns sized to their contents.
std::string parameter_table(const std::vector<protocol::ParameterInfo>& table) {
  std::vector<std::vector<std::string>> rows = {{"name", "default", "range", "integer", "description"}};
  for (const auto& p : table)
    rows.push_back({p.name, client::format_value(p.default_value), client::format_range(p),
                    p.integer ? "yes" : "no", p.description});
  std::vector<size_t> width(4, 0);
  for (const auto& r : rows)
    for (size_t c = 0; c < width.size(); ++c) width[c] = std::max(width[c], r[c].size());
  std::string out;
  for (const auto& r : rows) {
    std::string line = "    ";
    for (size_t c = 0; c < width.size(); ++c) line += pad(r[c], width[c] + 2);
    line += r[4];
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += line + "\n";
  }
  return out;
}

}  // namespace

client::Connection connect_for(const Args& args, const char* name) {
  client::ConnectOptions o;
  o.client_name = name;
  if (auto tf = args.get("token-file")) o.token_file = *tf;
  const double t = args.get_double("timeout", 10.0, kMinTimeoutSeconds, kMaxTimeoutSeconds);
  o.connect_timeout = o.io_timeout = std::chrono::milliseconds(static_cast<long long>(t * 1000.0));
  return client::Connection::connect(server_url(args.get_or("server", "")), o);
}

std::string channel_set(uint64_t mask) {
  std::string out;
  for (const auto& c : protocol::kChannels)
    if (mask & protocol::channel_bit(c.id)) out += (out.empty() ? "" : ",") + std::string(c.name);
  return out.empty() ? "-" : out;
}

std::string parameter_names(const protocol::Welcome& welcome, const protocol::PipelineInfo& pipeline) {
  if (!welcome.has_parameters) return "not announced (protocol 1.0 server)";
  std::string out;
  for (const auto& p : pipeline.parameters) out += (out.empty() ? "" : ", ") + p.name;
  return out.empty() ? "none" : out;
}

std::string pipelines_report(const protocol::Welcome& welcome, const std::string& only, const protocol::Stats* stats) {
  auto stat = [&](const std::string& name) -> std::optional<double> {
    if (stats)
      for (const auto& v : stats->values)
        if (v.name == name) return v.value;
    return std::nullopt;
  };
  std::string out, offered;
  for (const auto& p : welcome.pipelines) {
    offered += (offered.empty() ? "" : ", ") + p.name;
    if (!only.empty() && p.name != only) continue;
    out += (out.empty() ? "" : "\n") + p.name + "\n";
    out += "  requires  " + channel_set(p.required_channels) + "\n";
    out += "  optional  " + channel_set(p.optional_channels) + "\n";
    const auto kernels = stat("pipeline." + p.name + ".kernel_variants"), forms = stat("pipeline." + p.name + ".input_forms");
    if (kernels && forms)
      out += "  kernels   " + std::to_string(static_cast<uint64_t>(*kernels)) + " over " +
             std::to_string(static_cast<uint64_t>(*forms)) + " input forms (the warm-up compiles them all)\n";
    if (!welcome.has_parameters)
      out += "  parameters: not announced (the server speaks protocol 1.0; see docs/pipelines.md)\n";
    else if (p.parameters.empty())
      out += "  parameters: none\n";
    else
      out += "  parameters:\n" + parameter_table(p.parameters);
  }
  if (!only.empty() && out.empty())
    throw UsageError("the server offers no pipeline '" + only + "'; it offers: " + (offered.empty() ? "none" : offered));
  return out;
}

}  // namespace dn::cli
