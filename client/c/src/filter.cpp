// The filter: a pipeline, its images and parameters, and the session they
// open (dnCommitFilter) on the device's connection.
#include <cmath>
#include <memory>
#include <string>

#include "handles.hpp"

namespace dn::capi {
namespace {

using protocol::ChannelId;

constexpr protocol::Mat4 kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

// The names of the images a channel mask stands for.
std::string image_names(uint64_t mask) {
  std::string out;
  for (const auto& c : protocol::kChannels)
    if (uint32_t(c.id) < protocol::kChannelIdLimit && (mask & protocol::channel_bit(c.id)))
      out += (out.empty() ? "" : ", ") + image_name(c.id);
  return out;
}

std::string size_text(const Image& i) { return std::to_string(i.width) + "x" + std::to_string(i.height); }

// Settings of the C layer itself, taken by every pipeline.
constexpr const char* kHdr = "hdr";
constexpr const char* kMotionConvention = "motion_convention";
constexpr const char* kShareInput = "share_input";
constexpr const char* kSettingsNote = " (and the filter settings hdr, motion_convention, share_input)";

// Sets a value of any of the dnSetFilter1* kinds.
void set_value(DNFilterImpl& f, const std::string& name, double value) {
  if (name == kHdr) {
    if (value == 0)
      throw CError{DN_ERROR_INVALID_ARGUMENT,
                   "'hdr' must be true: the input is always linear scene-referred HDR radiance"};
    return;
  }
  if (name == kShareInput) {
    f.share_input = value != 0;
    return;
  }
  if (name == kMotionConvention) {
    if (!(value >= 0 && value <= 2 && value == std::floor(value)))
      throw CError{DN_ERROR_INVALID_ARGUMENT,
                   "'motion_convention' is " + client::format_value(value) +
                       ", expected a DNMotionConvention: DN_MOTION_PIXELS_TO_PREVIOUS (0), "
                       "DN_MOTION_PIXELS_TO_NEXT (1) or DN_MOTION_UV_TO_PREVIOUS (2)"};
    f.motion = static_cast<protocol::MotionConvention>(int(value));
    return;
  }
  // A pipeline parameter: checked now against the server's table by the
  // client library's own check (a server without tables checks at commit).
  const protocol::Welcome& welcome = f.device->connection->welcome();
  client::SessionDesc one;
  one.pipeline = f.pipeline;
  one.parameter(name, value);
  try {
    client::check_parameters(welcome, one);
  } catch (const client::Error& e) {
    std::string message = e.server_message();
    if (client::find_parameters(welcome, f.pipeline) && message.find("has no parameter") != std::string::npos)
      message += kSettingsNote;
    throw CError{DN_ERROR_INVALID_ARGUMENT, message};
  }
  for (auto& p : f.parameters)
    if (p.name == name) {
      p.value = value;
      return;
    }
  f.parameters.push_back({name, value});
}

double get_value(const DNFilterImpl& f, const std::string& name) {
  if (name == kHdr) return 1;
  if (name == kMotionConvention) return double(f.motion);
  if (name == kShareInput) return f.share_input ? 1 : 0;
  for (const auto& p : f.parameters)
    if (p.name == name) return p.value;
  const auto* table = client::find_parameters(f.device->connection->welcome(), f.pipeline);
  if (!table)
    throw CError{DN_ERROR_INVALID_ARGUMENT, "parameter '" + name + "' is not set and the server (protocol 1.0) "
                                            "announced no defaults"};
  for (const auto& p : *table)
    if (p.name == name) return p.default_value;
  std::string names;
  for (const auto& p : *table) names += (names.empty() ? "" : ", ") + p.name;
  throw CError{DN_ERROR_INVALID_ARGUMENT, "pipeline '" + f.pipeline + "' has no parameter '" + name +
                                              "'; valid names: " + (names.empty() ? "none" : names) +
                                              kSettingsNote};
}

void check_connected(const DNDeviceImpl& d) {
  if (!d.connection)
    throw CError{DN_ERROR_INVALID_OPERATION, "the device is not connected: dnCommitDevice has not succeeded"};
}

}  // namespace

const protocol::PipelineInfo& pipeline_info(const DNFilterImpl& f) {
  check_connected(*f.device);
  const protocol::PipelineInfo* p = f.device->connection->find_pipeline(f.pipeline);
  if (!p)
    throw CError{DN_ERROR_INVALID_ARGUMENT, "the server at " + f.device->connection->endpoint() +
                                                " no longer offers pipeline '" + f.pipeline + "'"};
  return *p;
}

client::SessionDesc describe(const DNFilterImpl& f) {
  const protocol::PipelineInfo& p = pipeline_info(f);
  const std::string pipeline = "pipeline '" + f.pipeline + "'";
  if (!f.output)
    throw CError{DN_ERROR_INVALID_ARGUMENT, "the 'output' image is not set (dnSetSharedFilterImage(filter, "
                                            "\"output\", ...))"};
  client::SessionDesc desc;
  desc.width = f.output->width;
  desc.height = f.output->height;
  desc.pipeline = f.pipeline;
  desc.output_format = wire_format(f.output->format);
  uint64_t given = 0;
  for (const auto& [id, image] : f.inputs) {
    if (image.width != desc.width || image.height != desc.height)
      throw CError{DN_ERROR_INVALID_ARGUMENT, "image '" + image.name + "' is " + size_text(image) +
                                                  ", but image 'output' is " + size_text(*f.output) +
                                                  ": all images must have one size"};
    if (!((p.required_channels | p.optional_channels) & protocol::channel_bit(id)))
      throw CError{DN_ERROR_INVALID_ARGUMENT, pipeline + " does not take image '" + image.name +
                                                  "'; it takes " +
                                                  image_names(p.required_channels | p.optional_channels)};
    desc.channel(id, wire_format(image.format));
    given |= protocol::channel_bit(id);
  }
  if (const uint64_t missing = p.required_channels & ~given)
    throw CError{DN_ERROR_INVALID_ARGUMENT, pipeline + " requires image '" + image_names(missing & -missing) +
                                                "', which is not set (required: " + image_names(p.required_channels) +
                                                "; not set: " + image_names(missing) + ")"};
  desc.parameters = f.parameters;
  desc.share_input = f.share_input;
  return desc;
}

bool same_session(const client::SessionDesc& a, const client::SessionDesc& b) {
  if (a.width != b.width || a.height != b.height || a.pipeline != b.pipeline || a.output_format != b.output_format ||
      a.share_input != b.share_input ||
      a.channels.size() != b.channels.size() || a.parameters.size() != b.parameters.size())
    return false;
  for (size_t i = 0; i < a.channels.size(); ++i)
    if (a.channels[i].id != b.channels[i].id || a.channels[i].format != b.channels[i].format) return false;
  for (size_t i = 0; i < a.parameters.size(); ++i)
    if (a.parameters[i].name != b.parameters[i].name || a.parameters[i].value != b.parameters[i].value) return false;
  return true;
}

}  // namespace dn::capi

using namespace dn;
using namespace dn::capi;

extern "C" {

DN_API DNFilter dnNewFilter(DNDevice device, const char* type) {
  return guarded(device, "dnNewFilter", static_cast<DNFilter>(nullptr), [&]() -> DNFilter {
    const std::string pipeline = required_name(type, "filter type");
    if (!device->connection)
      throw CError{DN_ERROR_INVALID_OPERATION, "the device is not committed: call dnCommitDevice first"};
    if (!device->connection->find_pipeline(pipeline)) {
      std::string names;
      for (const auto& p : device->connection->welcome().pipelines) names += (names.empty() ? "" : ", ") + p.name;
      throw CError{DN_ERROR_INVALID_ARGUMENT, "unknown filter type '" + pipeline + "': the server at " +
                                                  device->connection->endpoint() + " offers the pipelines " + names};
    }
    auto f = std::make_unique<DNFilterImpl>();
    f->device = device;
    f->pipeline = pipeline;
    f->view = kIdentity;
    f->projection = kIdentity;
    device->filters.push_back(f.get());
    device->refs.fetch_add(1);
    return f.release();
  });
}

DN_API void dnRetainFilter(DNFilter filter) {
  if (!filter) return record_error(nullptr, "dnRetainFilter", DN_ERROR_INVALID_ARGUMENT, "the filter is NULL");
  filter->refs.fetch_add(1);
}

DN_API void dnReleaseFilter(DNFilter filter) {
  if (!filter) return record_error(nullptr, "dnReleaseFilter", DN_ERROR_INVALID_ARGUMENT, "the filter is NULL");
  if (filter->refs.fetch_sub(1) != 1) return;
  DNDeviceImpl* device = filter->device;
  {
    std::lock_guard<std::recursive_mutex> lock(device->mutex);
    std::erase(device->filters, filter);
    delete filter;  // the session's destructor sends CLOSE_SESSION without waiting
  }
  dnReleaseDevice(device);
}

DN_API void dnSetFilter1b(DNFilter filter, const char* name, bool value) {
  guarded_filter_void(filter, "dnSetFilter1b", [&](DNFilterImpl& f) {
    check_connected(*f.device);
    set_value(f, required_name(name), value ? 1.0 : 0.0);
  });
}

DN_API void dnSetFilter1i(DNFilter filter, const char* name, int value) {
  guarded_filter_void(filter, "dnSetFilter1i", [&](DNFilterImpl& f) {
    check_connected(*f.device);
    set_value(f, required_name(name), double(value));
  });
}

DN_API void dnSetFilter1f(DNFilter filter, const char* name, float value) {
  guarded_filter_void(filter, "dnSetFilter1f", [&](DNFilterImpl& f) {
    check_connected(*f.device);
    set_value(f, required_name(name), double(value));
  });
}

DN_API float dnGetFilter1f(DNFilter filter, const char* name) {
  return guarded_filter(filter, "dnGetFilter1f", 0.0f, [&](DNFilterImpl& f) {
    check_connected(*f.device);
    return float(get_value(f, required_name(name)));
  });
}

DN_API int dnGetFilter1i(DNFilter filter, const char* name) {
  return guarded_filter(filter, "dnGetFilter1i", 0, [&](DNFilterImpl& f) {
    check_connected(*f.device);
    return int(std::lround(get_value(f, required_name(name))));
  });
}

DN_API void dnCommitFilter(DNFilter filter) {
  guarded_filter_void(filter, "dnCommitFilter", [&](DNFilterImpl& f) {
    DNDeviceImpl& d = *f.device;
    check_connected(d);
    const client::SessionDesc desc = describe(f);
    const bool live = f.session && f.session_generation == d.generation && d.connection->is_open();
    if (live && same_session(desc, f.committed)) return;  // keeps the session and its history
    // Frames in flight on the old session are collected (outputs written) first.
    if (live) sync_filter(f, "dnCommitFilter");
    f.pending.clear();
    f.session.reset();  // CLOSE_SESSION, not waited for
    f.watch_key.clear();
    f.watch_command.clear();
    f.samples.reset();
    f.session = d.connection->open_session(desc);
    f.session_generation = d.generation;
    f.committed = desc;
    f.watch_key = f.session->watch_key();
    f.watch_command = f.session->watch_command();
    f.reset_next = false;  // a new session starts without history anyway
  });
}

}  // extern "C"
