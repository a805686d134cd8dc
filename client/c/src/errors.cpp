// Errors: the first unqueried one kept per device (OIDN's rule), every one
// passed to the device's error function, exceptions translated to codes.
#include <cstdio>
#include <exception>
#include <new>
#include <string>

#include "handles.hpp"

namespace dn::capi {
namespace {

// Errors of calls given a NULL handle (and of dnNewDevice running out of
// memory): read with dnGetDeviceError(NULL, ...), per thread as in OIDN.
struct ThreadErrors {
  DNError error = DN_ERROR_NONE;
  std::string message, queried;
};
thread_local ThreadErrors t_errors;

}  // namespace

DNError error_code(const client::Error& e) {
  using protocol::ErrorCode;
  switch (e.kind()) {
    case client::ErrorKind::Transport: return DN_ERROR_CONNECTION;
    case client::ErrorKind::Protocol: return DN_ERROR_PROTOCOL;
    case client::ErrorKind::Server:
    case client::ErrorKind::Usage: break;
  }
  switch (e.code()) {
    case ErrorCode::UnknownPipeline:
    case ErrorCode::InvalidParameter:
    case ErrorCode::InvalidChannel:
    case ErrorCode::MissingChannel:
    case ErrorCode::UnknownSession:
      return DN_ERROR_INVALID_ARGUMENT;
    case ErrorCode::OutOfOrder:
      return DN_ERROR_INVALID_OPERATION;
    default:
      return e.kind() == client::ErrorKind::Usage ? DN_ERROR_INVALID_ARGUMENT : DN_ERROR_SERVER;
  }
}

std::pair<DNError, std::string> describe_current_exception() {
  try {
    throw;
  } catch (const CError& e) {
    return {e.code, e.message};
  } catch (const client::Error& e) {
    return {error_code(e), e.what()};
  } catch (const std::bad_alloc&) {
    return {DN_ERROR_OUT_OF_MEMORY, "out of memory"};
  } catch (const std::exception& e) {
    return {DN_ERROR_UNKNOWN, std::string("internal error: ") + e.what()};
  } catch (...) {
    return {DN_ERROR_UNKNOWN, "internal error: unknown exception"};
  }
}

void record_error(DNDeviceImpl* device, const char* where, DNError code, const std::string& message) noexcept {
  try {
    std::string text = std::string(where) + ": " + message;
    if (!device) {
      if (t_errors.error == DN_ERROR_NONE) {
        t_errors.error = code;
        t_errors.message = std::move(text);
      }
      return;
    }
    std::lock_guard<std::recursive_mutex> lock(device->mutex);
    if (device->error_function) device->error_function(device->error_user, code, text.c_str());
    if (device->error == DN_ERROR_NONE) {
      device->error = code;
      device->error_message = std::move(text);
    }
  } catch (...) {
    // Out of memory while building the message: keep the code at least.
    if (device && device->error == DN_ERROR_NONE) device->error = code;
  }
}

std::string required_name(const char* name, const char* what) {
  if (!name) throw CError{DN_ERROR_INVALID_ARGUMENT, std::string("the ") + what + " is NULL"};
  return name;
}

}  // namespace dn::capi

using namespace dn::capi;

extern "C" {

DN_API void dnSetDeviceErrorFunction(DNDevice device, DNErrorFunction func, void* userPtr) {
  guarded_void(device, "dnSetDeviceErrorFunction", [&] {
    device->error_function = func;
    device->error_user = userPtr;
  });
}

DN_API DNError dnGetDeviceError(DNDevice device, const char** outMessage) {
  try {
    if (!device) {
      const DNError code = t_errors.error;
      t_errors.queried = std::move(t_errors.message);
      t_errors.message.clear();
      t_errors.error = DN_ERROR_NONE;
      if (outMessage) *outMessage = t_errors.queried.c_str();
      return code;
    }
    std::lock_guard<std::recursive_mutex> lock(device->mutex);
    const DNError code = device->error;
    device->queried_message = std::move(device->error_message);
    device->error_message.clear();
    device->error = DN_ERROR_NONE;
    if (outMessage) *outMessage = device->queried_message.c_str();
    return code;
  } catch (...) {
    if (outMessage) *outMessage = "";
    return DN_ERROR_UNKNOWN;
  }
}

}  // extern "C"
