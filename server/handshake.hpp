// The server's side of the handshake: the WELCOME it announces (limits,
// pipelines and their parameters) from its options and the pipeline registry.
#pragma once

#include <cstdint>
#include <string>

#include "dn/protocol/messages.hpp"
#include "server/options.hpp"

namespace dn::server {

// client_minor is the minor version of the client's HELLO header: the
// parameter tables (protocol 1.1) go only to clients that know them.
protocol::Welcome make_welcome(const ServerOptions& options, const std::string& device_name, uint8_t client_minor);

}  // namespace dn::server
