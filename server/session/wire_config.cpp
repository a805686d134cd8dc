#include "server/session/wire_config.hpp"

#include <string_view>

#include "pipelines/auto_choice.hpp"

namespace dn::server {

// The wire's "auto" is the pipelines' (the name passes through unchanged).
static_assert(std::string_view(protocol::kAutoPipeline) == pipelines::kAutoPipeline);

pipelines::SessionConfig session_config(const protocol::OpenSession& m) {
  pipelines::SessionConfig c{m.width, m.height, m.pipeline, m.output_format, {}, {}};
  for (const protocol::ChannelDecl& d : m.channels) c.channels.push_back({d.id, d.format});
  for (const protocol::Parameter& p : m.parameters) c.parameters.push_back({p.name, p.value});
  return c;
}

std::vector<protocol::ChannelDecl> channel_decls(const pipelines::SessionConfig& config) {
  std::vector<protocol::ChannelDecl> out;
  for (const pipelines::InputChannel& c : config.channels) out.push_back({c.id, c.format});
  return out;
}

protocol::ErrorCode error_code(pipelines::ConfigProblem problem) {
  using P = pipelines::ConfigProblem;
  using protocol::ErrorCode;
  switch (problem) {
    case P::UnknownPipeline: return ErrorCode::UnknownPipeline;
    case P::MissingChannel: return ErrorCode::MissingChannel;
    case P::InvalidChannel: return ErrorCode::InvalidChannel;
    case P::InvalidParameter: return ErrorCode::InvalidParameter;
    case P::LimitExceeded: return ErrorCode::LimitExceeded;
  }
  return ErrorCode::Internal;
}

std::string open_session_field(const std::string& config_field) { return "OPEN_SESSION." + config_field; }

}  // namespace dn::server
