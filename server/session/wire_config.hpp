// OPEN_SESSION's fields as a pipeline's SessionConfig and back: the one place
// where the protocol's declaration and error codes meet the pipelines' own.
#pragma once

#include <string>
#include <vector>

#include "dn/protocol/messages.hpp"
#include "pipelines/pipeline.hpp"

namespace dn::server {

pipelines::SessionConfig session_config(const protocol::OpenSession& m);
// The channels as a SESSION reply declares them.
std::vector<protocol::ChannelDecl> channel_decls(const pipelines::SessionConfig& config);

// A refused configuration as ERROR fields: its code, and its SessionConfig
// field as the OPEN_SESSION field it came from ("channels[2].id" ->
// "OPEN_SESSION.channels[2].id").
protocol::ErrorCode error_code(pipelines::ConfigProblem problem);
std::string open_session_field(const std::string& config_field);

}  // namespace dn::server
