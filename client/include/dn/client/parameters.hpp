// Pipeline parameters as the server announces them (WELCOME, protocol 1.1),
// and the check Connection::open_session makes with them before sending.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "dn/client/session_desc.hpp"
#include "dn/protocol/messages.hpp"

namespace dn::client {

// The parameter table of `pipeline`; nullptr when the server sent no tables
// (a protocol 1.0 server) or offers no such pipeline.
const std::vector<protocol::ParameterInfo>* find_parameters(const protocol::Welcome& welcome,
                                                            std::string_view pipeline);

// A parameter's value ("%g") and inclusive range ("[min, max]") as the
// client's messages and `dn pipelines` print them.
std::string format_value(double value);
std::string format_range(const protocol::ParameterInfo& parameter);

// How a pipeline takes sample statistics over demodulated samples
// (docs/protocol.md §7.7): told by its parameter "demodulated"; not at all,
// because it only carries them (the statistics are optional to it and it has
// no such parameter: passthrough); or not safely, because it requires them
// but cannot be told (a server older than the parameter).
enum class DemodulatedStatistics { ByParameter, NotRead, Unsupported };
inline constexpr std::string_view kDemodulatedParameter = "demodulated";
DemodulatedStatistics demodulated_statistics(const protocol::PipelineInfo& pipeline);

// Checks desc.parameters against the table of desc.pipeline: every name known
// (else the error lists the valid names), given once, every value finite,
// within [min, max] and integral where required. Throws Error (Usage,
// InvalidParameter, field "OPEN_SESSION.parameters[i].name" or ".value").
// Does nothing when there is no table: the server then checks.
void check_parameters(const protocol::Welcome& welcome, const SessionDesc& desc);

}  // namespace dn::client
