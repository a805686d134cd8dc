// What the C handles point at, and the one way every API function runs its
// body: under the device's lock, with every exception turned into the
// device's error (never across the C boundary).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <deque>
#include <exception>
#include <map>
#include <mutex>
#include <new>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "dn/client/client.hpp"
#include "dn/dn.h"

namespace dn::capi {

// An error the C layer raises itself (the client library's are client::Error).
struct CError {
  DNError code;
  std::string message;
};

// One shared image: where its pixels are, as dnSetSharedFilterImage gave it.
struct Image {
  std::string name;  // as the caller spelled it ("color" or "radiance")
  protocol::ChannelId id = protocol::ChannelId::Radiance;
  DNFormat format = DN_FORMAT_UNDEFINED;
  uint8_t* data = nullptr;  // devPtr + byteOffset
  uint32_t width = 0, height = 0;
  size_t pixel_stride = 0, row_stride = 0;  // resolved: never 0
};

}  // namespace dn::capi

struct DNFilterImpl;

struct DNDeviceImpl {
  std::atomic<int> refs{1};
  std::recursive_mutex mutex;

  std::string url;  // as given, or the default
  bool url_from_environment = false;  // the default came from $DN_SERVER (said in its errors)
  dn::client::ConnectOptions options;
  std::optional<dn::client::Connection> connection;  // set by dnCommitDevice
  uint64_t generation = 0;  // connections made so far: a session of an older one is gone
  std::vector<DNFilterImpl*> filters;                // for dnSyncDevice

  // The first unqueried error (OIDN's rule) and the callback.
  DNError error = DN_ERROR_NONE;
  std::string error_message;
  std::string queried_message;  // what the last dnGetDeviceError handed out
  DNErrorFunction error_function = nullptr;
  void* error_user = nullptr;

  std::string string_value;  // what the last dnGetDevice1s handed out
};

struct DNFilterImpl {
  std::atomic<int> refs{1};
  DNDeviceImpl* device = nullptr;
  std::string pipeline;

  std::map<dn::protocol::ChannelId, dn::capi::Image> inputs;  // by channel: one image per channel
  std::optional<dn::capi::Image> output;
  std::vector<dn::protocol::Parameter> parameters;  // in the order first set
  dn::protocol::MotionConvention motion = dn::protocol::MotionConvention::PixelsToPrevious;
  bool share_input = false;  // SessionDesc::share_input: watchers also see the noisy colour

  // The open session and the description it was opened with.
  std::optional<dn::client::Session> session;
  dn::client::SessionDesc committed;
  uint64_t session_generation = 0;  // the device's connection the session was opened on
  std::string watch_key, watch_command;

  // The next frame's camera and flags.
  dn::protocol::Mat4 view{}, projection{};
  std::array<float, 2> jitter{};
  bool reset_next = false;

  // Output images of the frames sent by dnExecuteFilterAsync, oldest first.
  std::deque<dn::capi::Image> pending;
  // RESULT.samples of the last output written (dnGetFilterSamples).
  std::optional<dn::protocol::SampleCounts> samples;
  std::vector<std::vector<uint8_t>> scratch;  // packed copies of strided inputs
};

namespace dn::capi {

// Records an error on `device` (nullptr: this thread's slot) and calls its
// error function. `where` is the API function, prefixed to the message.
void record_error(DNDeviceImpl* device, const char* where, DNError code, const std::string& message) noexcept;
// The code and message of the exception being handled.
std::pair<DNError, std::string> describe_current_exception();
DNError error_code(const client::Error& e);

// Runs `body()` under the device's lock; an exception becomes the device's
// error and `fallback` is returned.
template <class R, class F>
R guarded(DNDeviceImpl* device, const char* where, R fallback, F&& body) {
  if (!device) {
    record_error(nullptr, where, DN_ERROR_INVALID_ARGUMENT, "the device is NULL");
    return fallback;
  }
  std::lock_guard<std::recursive_mutex> lock(device->mutex);
  try {
    return body();
  } catch (...) {
    auto [code, message] = describe_current_exception();
    record_error(device, where, code, message);
    return fallback;
  }
}

template <class F>
void guarded_void(DNDeviceImpl* device, const char* where, F&& body) {
  guarded(device, where, 0, [&] {
    body();
    return 0;
  });
}

// The same for a filter's call: errors go to the filter's device.
template <class R, class F>
R guarded_filter(DNFilterImpl* filter, const char* where, R fallback, F&& body) {
  if (!filter) {
    record_error(nullptr, where, DN_ERROR_INVALID_ARGUMENT, "the filter is NULL");
    return fallback;
  }
  return guarded(filter->device, where, fallback, [&] { return body(*filter); });
}

template <class F>
void guarded_filter_void(DNFilterImpl* filter, const char* where, F&& body) {
  guarded_filter(filter, where, 0, [&](DNFilterImpl& f) {
    body(f);
    return 0;
  });
}

// A name argument that must not be NULL.
std::string required_name(const char* name, const char* what = "name");

// ---- images.cpp ---------------------------------------------------------------
// The channel an image name stands for (OIDN's "color" is radiance); throws
// CError naming the accepted names.
protocol::ChannelId channel_for_image(const std::string& name);
// The name a channel's image is spoken of by (OIDN's where OIDN has one).
std::string image_name(protocol::ChannelId id);
protocol::Format wire_format(DNFormat format);
// The image's pixels as one packed plane (a view of the caller's memory when
// it is packed already, else a copy in `scratch`).
std::span<const uint8_t> packed_plane(const Image& image, std::vector<uint8_t>& scratch);
// Writes a result's RGB output into `image` with its strides.
void write_output(const client::Result& result, const Image& image);

// ---- filter.cpp ---------------------------------------------------------------
// The session the filter's images and parameters describe; throws CError
// naming an image that is missing or of another size.
client::SessionDesc describe(const DNFilterImpl& filter);
bool same_session(const client::SessionDesc& a, const client::SessionDesc& b);
const protocol::PipelineInfo& pipeline_info(const DNFilterImpl& filter);

// ---- execute.cpp --------------------------------------------------------------
// Collects every frame in flight and writes their outputs (dnSyncFilter's body).
// A frame the server refused is recorded (as `where`) and the others collected;
// a lost connection throws.
void sync_filter(DNFilterImpl& filter, const char* where);

}  // namespace dn::capi
