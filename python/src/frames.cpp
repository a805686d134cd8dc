// NumPy arrays <-> the client's frames and results: channel names (the
// protocol's table, protocol::kChannels), plane shapes and dtypes, camera
// matrices, and Result -> dn.Result.
#include <cstring>

#include "common.hpp"
#include "dn/protocol/codec.hpp"

namespace dn::python {

using protocol::ChannelId;
using protocol::Format;

std::string channel_name(ChannelId id) {
  const protocol::ChannelInfo* c = protocol::find_channel(id);
  return c ? std::string(c->name) : std::to_string(unsigned(id));
}

namespace {

std::string sendable_channel_list() {
  std::string names;
  for (const auto& c : protocol::kChannels)
    if (c.id != ChannelId::Output) names += (names.empty() ? "" : ", ") + std::string(c.name);
  return names;
}

std::string shape_string(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

std::string expected_shape(uint32_t h, uint32_t w, uint32_t components) {
  return "(" + std::to_string(h) + ", " + std::to_string(w) +
         (components == 1 ? ") or (" + std::to_string(h) + ", " + std::to_string(w) + ", 1)"
                          : ", " + std::to_string(components) + ")");
}

// The plane as a C-contiguous native float32 or float16 array: float32 and
// float16 keep their type, float64 (NumPy's default) becomes float32, any
// other dtype is refused (TypeError naming the channel).
py::array plane_array(const py::handle& value, const std::string& channel, Format& format) {
  py::array a = py::array::ensure(value);
  if (!a) {
    PyErr_Clear();
    throw py::type_error("channel '" + channel + "': expected a NumPy array (float32, float16 or float64), got " +
                         std::string(py::str(py::type::of(value).attr("__name__"))));
  }
  const py::dtype dt = a.dtype();
  if (dt.kind() == 'f' && dt.itemsize() == 2) {
    format = Format::F16;
    py::module_ np = py::module_::import("numpy");
    return np.attr("ascontiguousarray")(a, py::dtype("=f2"));
  }
  if (dt.kind() == 'f' && (dt.itemsize() == 4 || dt.itemsize() == 8)) {
    format = Format::F32;
    return py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
  }
  throw py::type_error("channel '" + channel + "': dtype " + std::string(py::str(py::handle(dt))) +
                       " is not supported; give float32 or float16 (float64 is converted to float32)");
}

}  // namespace

const protocol::ChannelInfo& channel_by_name(const std::string& name) {
  const protocol::ChannelInfo* c = protocol::find_channel(std::string_view(name));
  if (!c || c->id == ChannelId::Output)
    throw client::Error::usage(protocol::ErrorCode::InvalidChannel, "",
                               "unknown channel '" + name + "'; channels are: " + sendable_channel_list());
  return *c;
}

Format parse_format(const py::handle& value, const std::string& what) {
  if (py::isinstance<py::str>(value)) {
    const std::string s = value.cast<std::string>();
    if (s == "f32" || s == "float32") return Format::F32;
    if (s == "f16" || s == "float16") return Format::F16;
  } else if (!value.is_none()) {
    // A NumPy dtype or scalar type: np.float32, np.float16, np.dtype("f2").
    try {
      const py::dtype dt = py::dtype::from_args(py::reinterpret_borrow<py::object>(value));
      if (dt.kind() == 'f' && dt.itemsize() == 4) return Format::F32;
      if (dt.kind() == 'f' && dt.itemsize() == 2) return Format::F16;
    } catch (const py::error_already_set&) {
    }
  }
  throw client::Error::usage(what + ": format " + std::string(py::str(py::repr(value))) +
                             " is not one of 'f32', 'f16' (or numpy.float32, numpy.float16)");
}

const char* format_name(Format f) { return f == Format::F16 ? "f16" : "f32"; }

py::list channel_names(uint64_t mask) {
  py::list out;
  for (const auto& c : protocol::kChannels)
    if (uint32_t(c.id) < protocol::kChannelIdLimit && (mask & protocol::channel_bit(c.id))) out.append(std::string(c.name));
  return out;
}

protocol::MotionConvention parse_motion(const std::string& name) {
  if (name == "to-previous") return protocol::MotionConvention::PixelsToPrevious;
  if (name == "to-next") return protocol::MotionConvention::PixelsToNext;
  if (name == "uv") return protocol::MotionConvention::UvToPrevious;
  throw client::Error::usage("motion='" + name + "' is not one of 'to-previous', 'to-next', 'uv'");
}

protocol::Mat4 to_mat4(const py::handle& m, const char* what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(m);
  if (!a) {
    PyErr_Clear();
    throw client::Error::usage(std::string(what) + ": expected a 4x4 matrix (array-like, indexed [row, column])");
  }
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
    throw client::Error::usage(std::string(what) + ": expected a 4x4 matrix (indexed [row, column]), got shape " +
                               shape_string(a));
  protocol::Mat4 out{};
  auto r = a.unchecked<2>();
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col) out[size_t(col * 4 + row)] = float(r(row, col));  // column-major (GLM)
  return out;
}

py::array_t<float> from_mat4(const protocol::Mat4& m) {
  py::array_t<float> a({4, 4});
  auto w = a.mutable_unchecked<2>();
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 4; ++col) w(row, col) = m[size_t(col * 4 + row)];
  return a;
}

std::array<float, 2> to_vec2(const py::handle& v, const char* what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
  if (!a || a.size() != 2) {
    PyErr_Clear();
    throw client::Error::usage(std::string(what) + ": expected two numbers (x, y) in pixels");
  }
  return {float(a.data()[0]), float(a.data()[1])};
}

PreparedFrame prepare_frame(const client::Session& session, const py::handle& frame_in, const FrameOptions& opt) {
  PreparedFrame out;
  client::FrameInput& in = out.input;
  const uint32_t w = session.width(), h = session.height();

  // A dn.Frame (dn.read_frame) brings its planes and camera; keywords win.
  py::dict planes;
  const LoadedFrame* loaded = nullptr;
  if (py::isinstance<LoadedFrame>(frame_in)) {
    loaded = &frame_in.cast<const LoadedFrame&>();
    planes = loaded->planes;
  } else if (py::isinstance<py::dict>(frame_in)) {
    planes = py::reinterpret_borrow<py::dict>(frame_in);
  } else {
    throw py::type_error("frame: expected a dict of channel name -> array, or a dn.Frame; got " +
                         std::string(py::str(py::type::of(frame_in).attr("__name__"))));
  }

  const protocol::Mat4 identity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  in.info.view = !opt.view.is_none() ? to_mat4(opt.view, "view")
                                     : (loaded && loaded->view ? *loaded->view : identity);
  in.info.projection = !opt.projection.is_none() ? to_mat4(opt.projection, "projection")
                                                 : (loaded && loaded->projection ? *loaded->projection : identity);
  if (!opt.jitter.is_none()) in.info.jitter = to_vec2(opt.jitter, "jitter");
  else if (loaded && loaded->jitter) in.info.jitter = *loaded->jitter;
  const bool prev_given = !opt.prev_view.is_none() || !opt.prev_projection.is_none();
  if (prev_given) {
    if (opt.prev_view.is_none() || opt.prev_projection.is_none())
      throw client::Error::usage("prev_view and prev_projection go together (or leave both out: the previous "
                                 "frame's camera is used)");
    in.fill_previous_camera = false;
    in.info.prev_view = to_mat4(opt.prev_view, "prev_view");
    in.info.prev_projection = to_mat4(opt.prev_projection, "prev_projection");
    if (!opt.prev_jitter.is_none()) in.info.prev_jitter = to_vec2(opt.prev_jitter, "prev_jitter");
  } else if (!opt.prev_jitter.is_none()) {
    throw client::Error::usage("prev_jitter needs prev_view and prev_projection");
  } else if (loaded && loaded->prev_view && loaded->prev_projection && opt.view.is_none()) {
    in.fill_previous_camera = false;
    in.info.prev_view = *loaded->prev_view;
    in.info.prev_projection = *loaded->prev_projection;
    in.info.prev_jitter = loaded->prev_jitter.value_or(std::array<float, 2>{});
  }
  in.info.motion = parse_motion(opt.motion);
  if (opt.reset) in.reset();
  in.frame_index = opt.frame_index;
  in.no_output = opt.no_output;

  // Every declared channel must be given; the session checks the rest
  // (declared, not twice, byte size) with the same words as the C++ library.
  std::string given;
  for (auto item : planes) {
    if (!py::isinstance<py::str>(item.first))
      throw py::type_error("frame: keys must be channel names (str), got " + std::string(py::repr(item.first)));
    channel_by_name(item.first.cast<std::string>());  // an unknown name first: it may be a misspelt declared one
    given += (given.empty() ? "" : ", ") + item.first.cast<std::string>();
  }
  for (const auto& decl : session.info().channels) {
    if (!planes.contains(channel_name(decl.id)))
      throw client::Error::usage(protocol::ErrorCode::MissingChannel, "FRAME.planes",
                                 "channel '" + channel_name(decl.id) + "' was declared when session " +
                                     std::to_string(session.id()) + " was opened but is missing from the frame (given: " +
                                     (given.empty() ? "none" : given) + ")");
  }

  size_t index = 0;
  for (auto item : planes) {
    const std::string name = item.first.cast<std::string>();
    const protocol::ChannelInfo& ci = channel_by_name(name);
    Format format = Format::F32;
    py::array a = plane_array(item.second, name, format);
    bool declared = false;
    for (const auto& d : session.info().channels) declared |= d.id == ci.id;
    if (declared) {  // an undeclared one is refused by Session::submit, which lists the declared channels
      const bool ok = a.ndim() >= 2 && a.shape(0) == py::ssize_t(h) && a.shape(1) == py::ssize_t(w) &&
                      ((a.ndim() == 3 && a.shape(2) == py::ssize_t(ci.components)) ||
                       (a.ndim() == 2 && ci.components == 1));
      if (!ok)
        throw client::Error::usage(protocol::ErrorCode::InvalidChannel, "FRAME.planes[" + std::to_string(index) + "]",
                                   "channel '" + name + "' has shape " + shape_string(a) + ", session " +
                                       std::to_string(session.id()) + " expects " +
                                       expected_shape(h, w, ci.components) + " (height, width" +
                                       (ci.components == 1 ? "" : ", components") + ")");
    }
    in.add(ci.id, format, a.data(), size_t(a.nbytes()));
    out.keep.push_back(std::move(a));
    ++index;
  }
  return out;
}

PyResult to_python(const client::Result& r) {
  PyResult out;
  out.session_id = r.session_id;
  out.frame_index = r.frame_index;
  out.width = r.width;
  out.height = r.height;
  out.format = format_name(r.format);
  if (r.has_output()) {
    py::array_t<float> image({py::ssize_t(r.height), py::ssize_t(r.width), py::ssize_t(3)});
    r.copy_rgb(std::span<float>(image.mutable_data(), size_t(image.size())));
    out.image = std::move(image);
  } else {
    out.image = py::none();
  }
  if (r.has_input()) {
    const std::vector<float> rgb = r.input_rgb();
    py::array_t<float> input({py::ssize_t(r.height), py::ssize_t(r.width), py::ssize_t(3)});
    std::copy(rgb.begin(), rgb.end(), input.mutable_data());
    out.input = std::move(input);
  } else {
    out.input = py::none();
  }
  for (const auto& t : r.timings) out.timings[py::str(t.name)] = t.milliseconds;
  out.samples = r.samples ? py::object(py::make_tuple(r.samples->min, r.samples->median)) : py::none();
  out.latency_ms = r.latency.count();
  out.total_timing_ms = r.total_timing_ms();
  return out;
}

void bind_frames(py::module_& m) {
  py::class_<PyResult>(m, "Result",
                       "A denoised frame: frame_index, image ((height, width, 3) float32, rows top-first, or None "
                       "for a no_output frame), timings (the server's per-pass and per-stage ms, by name), "
                       "latency_ms (from the start of sending to the arrival of the result; 0 for a watcher).")
      .def_readonly("session_id", &PyResult::session_id)
      .def_readonly("frame_index", &PyResult::frame_index)
      .def_readonly("width", &PyResult::width)
      .def_readonly("height", &PyResult::height)
      .def_readonly("format", &PyResult::format, "the output's wire format, 'f32' or 'f16' (image is float32 either way)")
      .def_readonly("image", &PyResult::image)
      .def_readonly("input", &PyResult::input,
                    "a watcher's copy from a session opened with share_input: the noisy radiance the owner sent, "
                    "(height, width, 3) float32; else None")
      .def_readonly("timings", &PyResult::timings)
      .def_readonly("samples", &PyResult::samples,
                    "(min, median) over the frame of the input frames each pixel's output rests on (its history "
                    "length, or a still pixel's running-mean count); None from a pipeline without a count")
      .def_readonly("latency_ms", &PyResult::latency_ms)
      .def_readonly("total_timing_ms", &PyResult::total_timing_ms)
      .def("__repr__", [](const PyResult& r) {
        return "<dn.Result frame " + std::to_string(r.frame_index) + " of session " + std::to_string(r.session_id) +
               ", " + std::to_string(r.width) + "x" + std::to_string(r.height) + ", server " +
               std::to_string(r.total_timing_ms) + " ms>";
      });

  py::dict channels;
  for (const auto& c : protocol::kChannels)
    if (c.id != ChannelId::Output) channels[py::str(std::string(c.name))] = c.components;
  m.attr("CHANNELS") = channels;
}

}  // namespace dn::python
