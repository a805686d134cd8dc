// The device: the server address and connect options, then one
// client::Connection (dnCommitDevice), shared by the device's filters.
#include <climits>
#include <cstdlib>
#include <new>
#include <string>

#include "handles.hpp"

namespace dn::capi {
namespace {

// The address without one given: $DN_SERVER, else where dnserver listens
// without --listen (the dn tool's rule, client/tools/ops_cmd.cpp).
std::string default_url(bool& from_environment) {
  if (const char* env = std::getenv("DN_SERVER"); env && *env) {
    from_environment = true;
    return env;
  }
  from_environment = false;
  return client::kDefaultServerUrl;
}

void check_url(const std::string& url, bool from_environment) {
  try {
    client::parse_endpoint(url);
  } catch (const client::Error& e) {
    throw CError{DN_ERROR_INVALID_ARGUMENT, (from_environment ? "$DN_SERVER: " : "") + std::string(e.what())};
  }
}

void check_not_committed(const DNDeviceImpl& d, const std::string& name) {
  if (d.connection)
    throw CError{DN_ERROR_INVALID_OPERATION,
                 "device setting '" + name + "' set after dnCommitDevice; device settings apply before it"};
}

const client::Connection& connected(const DNDeviceImpl& d, const std::string& name) {
  if (!d.connection)
    throw CError{DN_ERROR_INVALID_OPERATION, "'" + name + "' is known only after dnCommitDevice"};
  return *d.connection;
}

std::string pipeline_names(const protocol::Welcome& w) {
  std::string out;
  for (const auto& p : w.pipelines) out += (out.empty() ? "" : ",") + p.name;
  return out;
}

int as_int(uint64_t v) { return v > uint64_t(INT_MAX) ? INT_MAX : int(v); }

}  // namespace
}  // namespace dn::capi

using namespace dn;
using namespace dn::capi;

extern "C" {

DN_API DNDevice dnNewDevice(const char* url) {
  DNDeviceImpl* d = new (std::nothrow) DNDeviceImpl;
  if (!d) {
    record_error(nullptr, "dnNewDevice", DN_ERROR_OUT_OF_MEMORY, "out of memory");
    return nullptr;
  }
  guarded_void(d, "dnNewDevice", [&] {
    d->options.client_name = "dn-c";
    d->url = (url && *url) ? std::string(url) : default_url(d->url_from_environment);
    check_url(d->url, d->url_from_environment);  // recorded now, and again by dnCommitDevice
  });
  return d;
}

DN_API void dnRetainDevice(DNDevice device) {
  if (!device) return record_error(nullptr, "dnRetainDevice", DN_ERROR_INVALID_ARGUMENT, "the device is NULL");
  device->refs.fetch_add(1);
}

DN_API void dnReleaseDevice(DNDevice device) {
  if (!device) return record_error(nullptr, "dnReleaseDevice", DN_ERROR_INVALID_ARGUMENT, "the device is NULL");
  if (device->refs.fetch_sub(1) == 1) delete device;  // closes the connection
}

DN_API void dnSetDevice1s(DNDevice device, const char* name, const char* value) {
  guarded_void(device, "dnSetDevice1s", [&] {
    const std::string key = required_name(name);
    check_not_committed(*device, key);
    if (key == "token") {
      if (value) device->options.auth_token = value;
      else device->options.auth_token.reset();  // NULL: from the environment again
      return;
    }
    const std::string v = required_name(value, "value");
    if (key == "url") {
      device->url_from_environment = false;
      device->url = v.empty() ? default_url(device->url_from_environment) : v;
      check_url(device->url, device->url_from_environment);
    } else if (key == "token_file") {
      device->options.token_file = v;
    } else if (key == "client_name") {
      device->options.client_name = v;
    } else {
      throw CError{DN_ERROR_INVALID_ARGUMENT,
                   "unknown device setting '" + key + "' (string settings: url, token, token_file, client_name)"};
    }
  });
}

DN_API void dnSetDevice1i(DNDevice device, const char* name, int value) {
  guarded_void(device, "dnSetDevice1i", [&] {
    const std::string key = required_name(name);
    check_not_committed(*device, key);
    if (key == "connect_timeout_ms" || key == "io_timeout_ms") {
      const int least = key == "connect_timeout_ms" ? 1 : 0;
      if (value < least)
        throw CError{DN_ERROR_INVALID_ARGUMENT,
                     "device setting '" + key + "' is " + std::to_string(value) + ", must be at least " +
                         std::to_string(least)};
      (key == "connect_timeout_ms" ? device->options.connect_timeout : device->options.io_timeout) =
          client::Milliseconds(value);
    } else {
      throw CError{DN_ERROR_INVALID_ARGUMENT,
                   "unknown device setting '" + key + "' (integer settings: connect_timeout_ms, io_timeout_ms)"};
    }
  });
}

DN_API const char* dnGetDevice1s(DNDevice device, const char* name) {
  return guarded(device, "dnGetDevice1s", static_cast<const char*>(nullptr), [&]() -> const char* {
    const std::string key = required_name(name);
    if (key == "url") {
      device->string_value = device->connection ? device->connection->endpoint() : device->url;
    } else if (key == "server_version") {
      device->string_value = connected(*device, key).welcome().server_version;
    } else if (key == "device_name") {
      device->string_value = connected(*device, key).welcome().device_name;
    } else if (key == "pipelines") {
      device->string_value = pipeline_names(connected(*device, key).welcome());
    } else {
      throw CError{DN_ERROR_INVALID_ARGUMENT,
                   "unknown device property '" + key + "' (url, server_version, device_name, pipelines)"};
    }
    return device->string_value.c_str();
  });
}

DN_API int dnGetDevice1i(DNDevice device, const char* name) {
  return guarded(device, "dnGetDevice1i", 0, [&]() -> int {
    const std::string key = required_name(name);
    if (key == "version_major" || key == "version_minor") {
      const client::Connection& c = connected(*device, key);
      return key == "version_major" ? int(protocol::kVersionMajor) : int(c.protocol_minor());
    }
    const protocol::Limits* limits = nullptr;
    if (key == "max_width" || key == "max_height" || key == "max_frames_in_flight")
      limits = &connected(*device, key).welcome().limits;
    if (key == "max_width") return as_int(limits->max_width);
    if (key == "max_height") return as_int(limits->max_height);
    if (key == "max_frames_in_flight") return as_int(limits->max_frames_in_flight);
    throw CError{DN_ERROR_INVALID_ARGUMENT,
                 "unknown device property '" + key +
                     "' (version_major, version_minor, max_width, max_height, max_frames_in_flight)"};
  });
}

DN_API void dnCommitDevice(DNDevice device) {
  guarded_void(device, "dnCommitDevice", [&] {
    if (device->connection && device->connection->is_open()) return;
    // First commit, or again after the connection was lost: connect anew.
    // Filters open new sessions at their next dnCommitFilter.
    device->connection.reset();
    check_url(device->url, device->url_from_environment);
    device->connection = client::Connection::connect(device->url, device->options);
    ++device->generation;
  });
}

DN_API void dnSyncDevice(DNDevice device) {
  guarded_void(device, "dnSyncDevice", [&] {
    // Each filter's errors are recorded as they happen; go on with the others.
    for (DNFilterImpl* f : device->filters) {
      try {
        sync_filter(*f, "dnSyncDevice");
      } catch (...) {
        auto [code, message] = describe_current_exception();
        record_error(device, "dnSyncDevice", code, message);
      }
    }
  });
}

}  // extern "C"
