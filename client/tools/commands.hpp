// The dn subcommands. Each returns the process exit status; errors are thrown
// (UsageError -> status 2, anything else -> status 1) and printed by main().
#pragma once

#include <string>
#include <vector>

namespace dn::cli {

int run_denoise(const std::vector<std::string>& args);
int run_watch(const std::vector<std::string>& args);
int run_stats(const std::vector<std::string>& args);
int run_ping(const std::vector<std::string>& args);
int run_pipelines(const std::vector<std::string>& args);

// --server, or $DN_SERVER; UsageError when neither is set.
std::string server_url(const std::string& option_value);

}  // namespace dn::cli
