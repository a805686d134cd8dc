// The dn subcommands. Each returns the process exit status; errors are thrown
// (UsageError -> status 2, anything else -> status 1) and printed by main().
#pragma once

#include <string>
#include <vector>

#include "args.hpp"

namespace dn::cli {

int run_denoise(const std::vector<std::string>& args);
int run_watch(const std::vector<std::string>& args);
int run_preview(const std::vector<std::string>& args);
int run_stats(const std::vector<std::string>& args);
int run_ping(const std::vector<std::string>& args);
int run_pipelines(const std::vector<std::string>& args);
int run_capacity(const std::vector<std::string>& args);

// Exit statuses of every dn command.
inline constexpr int kExitOk = 0;
inline constexpr int kExitError = 1;              // the server, a file or the connection failed
inline constexpr int kExitUsage = 2;              // bad command line (UsageError)
inline constexpr int kExitThresholdExceeded = 3;  // dn denoise --fail: the output is too far from -r

// The range every --timeout SECONDS accepts.
inline constexpr double kMinTimeoutSeconds = 0.001;
inline constexpr double kMaxTimeoutSeconds = 1e6;

// --server, else $DN_SERVER, else client::kDefaultServerUrl; UsageError when
// the address is malformed.
std::string server_url(const std::string& option_value);

// The --server option of every command that connects; its help names the default.
Args::Spec server_option();

}  // namespace dn::cli
