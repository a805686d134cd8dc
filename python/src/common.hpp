// Shared declarations of the `dn` Python module (pybind11): the wrappers
// around dn::client objects, the lock that serialises calls on one
// connection, and the conversions between NumPy arrays and the client's
// frames, matrices and results. docs/client.md, "Python bindings".
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "dn/client/client.hpp"

namespace dn::python {

namespace py = pybind11;

// One per connection, shared with its sessions and watchers: the C++ objects
// of one connection must be used from one thread at a time (docs/client.md,
// "Threading"), and the module releases the GIL while they block, so every
// call that touches the socket holds this lock.
using ConnectionLock = std::shared_ptr<std::mutex>;

// Runs f() without the GIL and with the connection's lock held. The lock is
// given back before the GIL is taken again, so a thread holding it never
// waits for the GIL.
template <class F>
auto blocking(const ConnectionLock& lock, F&& f) -> decltype(f()) {
  py::gil_scoped_release release;
  std::lock_guard<std::mutex> guard(*lock);
  return f();
}

// ---- errors (errors.cpp) --------------------------------------------------------
void bind_errors(py::module_& m);

// ---- names (frames.cpp) -----------------------------------------------------------
const protocol::ChannelInfo& channel_by_name(const std::string& name);  // throws UsageError listing the names
std::string channel_name(protocol::ChannelId id);
protocol::Format parse_format(const py::handle& value, const std::string& what);  // "f32" | "f16"
const char* format_name(protocol::Format f);
py::list channel_names(uint64_t mask);
protocol::MotionConvention parse_motion(const std::string& name);

// ---- matrices (frames.cpp) ----------------------------------------------------------
// A 4x4 array-like indexed [row, column] (p' = M @ p, as NumPy and Blender's
// mathutils write it) to the protocol's column-major Mat4, and back.
protocol::Mat4 to_mat4(const py::handle& m, const char* what);
py::array_t<float> from_mat4(const protocol::Mat4& m);
std::array<float, 2> to_vec2(const py::handle& v, const char* what);

// ---- frames and results (frames.cpp) ---------------------------------------------------
// A frame read from an EXR through a preset (image_io.cpp, dn.read_frame).
struct LoadedFrame {
  std::string path, preset;
  int width = 0, height = 0;
  py::dict planes;      // channel name -> ndarray
  py::dict channels;    // channel name -> "f32" | "f16", for open_session
  py::dict parameters;  // session parameters the file implies (dnrender's demodulated statistics)
  py::dict mapping;     // channel name -> where it came from
  std::optional<protocol::Mat4> view, projection, prev_view, prev_projection;
  std::optional<std::array<float, 2>> jitter, prev_jitter;
  std::string camera_source;
  double camera_residual_px = 0.0;
};

// Per-frame options of submit()/denoise(), as Python keyword arguments.
struct FrameOptions {
  py::object view, projection, jitter, prev_view, prev_projection, prev_jitter;
  bool reset = false;
  std::optional<uint64_t> frame_index;
  std::string motion = "to-previous";
  bool no_output = false;
};

// A FrameInput whose planes point into arrays it keeps alive. Build it with
// the GIL held; submit it without.
struct PreparedFrame {
  client::FrameInput input;
  std::vector<py::array> keep;
};
PreparedFrame prepare_frame(const client::Session& session, const py::handle& frame, const FrameOptions& options);

struct PyResult {
  uint64_t session_id = 0, frame_index = 0;
  uint32_t width = 0, height = 0;
  std::string format;
  py::object image;  // (H, W, 3) float32, or None for a no_output frame
  py::object input;  // a watcher's copy when the owner shares its input: the noisy radiance, else None
  py::dict timings;  // name -> ms
  py::object samples;  // (min, median) input frames the output rests on (protocol 1.9), or None
  double latency_ms = 0.0, total_timing_ms = 0.0;
};
PyResult to_python(const client::Result& r);

void bind_frames(py::module_& m);

// ---- connection, session, watcher, image I/O ----------------------------------------------
void bind_connection(py::module_& m);
void bind_watcher(py::module_& m);
void bind_image_io(py::module_& m);

struct PyWatcher {
  std::optional<client::Watcher> watcher;
  ConnectionLock lock;
  std::string endpoint;               // the connection's, for a timeout's message
  std::chrono::milliseconds io_timeout{0};  // the connection's (0: forever), next()'s default
  bool ended = false;
  ~PyWatcher();
};

}  // namespace dn::python
