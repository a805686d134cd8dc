// What the operational commands (ping, stats, pipelines) share: connecting
// with --server/--token-file/--timeout, and describing the server's WELCOME.
#pragma once

#include <cstdint>
#include <string>

#include "args.hpp"
#include "dn/client/client.hpp"

namespace dn::cli {

// Connects to --server (or $DN_SERVER) as client `name`, with --token-file
// and --timeout SECONDS (default 10) applied.
client::Connection connect_for(const Args& args, const char* name);

// "radiance,albedo" for a channel mask; "-" when empty.
std::string channel_set(uint64_t mask);

// One line: the pipeline's parameter names, "none", or "not announced"
// when the server sent no tables (protocol 1.0).
std::string parameter_names(const protocol::Welcome& welcome, const protocol::PipelineInfo& pipeline);

// Every pipeline (or only `only`, when not empty) with its channels, its
// kernel variants when `stats` has them (pipeline.<name>.kernel_variants and
// .input_forms), and its parameter table: name, default, range, integer,
// description. Throws UsageError naming the pipelines offered when `only` is
// not one of them.
std::string pipelines_report(const protocol::Welcome& welcome, const std::string& only = {},
                             const protocol::Stats* stats = nullptr);

}  // namespace dn::cli
