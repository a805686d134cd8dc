// dn.connect, dn.Connection, dn.Session, dn.PipelineInfo, dn.ParameterInfo:
// a thin mirror of dn::client::Connection and Session (connection.hpp,
// session.hpp). Blocking calls run without the GIL (common.hpp, blocking()).
#include <cstdlib>

#include "common.hpp"

namespace dn::python {

using protocol::Format;

namespace {

struct PyConnection {
  std::optional<client::Connection> conn;
  ConnectionLock lock = std::make_shared<std::mutex>();
  std::chrono::milliseconds io_timeout{0};

  client::Connection& get() {
    if (!conn) throw client::Error::usage("the connection was closed");
    return *conn;
  }
  ~PyConnection() {
    std::lock_guard<std::mutex> guard(*lock);
    conn.reset();
  }
};

struct PySession {
  std::optional<client::Session> session;
  ConnectionLock lock;

  client::Session& get() {
    if (!session) throw client::Error::usage("the session was closed");
    return *session;
  }
  ~PySession() {
    // ~Session closes the session on the server without waiting for the reply.
    std::lock_guard<std::mutex> guard(*lock);
    session.reset();
  }
};

std::chrono::milliseconds seconds_to_ms(double s, const char* what) {
  if (!(s >= 0.0) || s > 1e9) throw client::Error::usage(std::string(what) + " must be a number of seconds >= 0");
  return std::chrono::milliseconds(static_cast<long long>(s * 1000.0 + 0.5));
}

// The default address, as the dn tool has it: $DN_SERVER, else protocol::kDefaultServerUrl.
std::string default_url() {
  const char* env = std::getenv("DN_SERVER");
  return env && *env ? env : client::kDefaultServerUrl;
}

std::unique_ptr<PyConnection> connect(const std::optional<std::string>& url, const std::optional<std::string>& token,
                     const std::optional<std::string>& token_file, const std::string& client_name,
                     double connect_timeout, double io_timeout, uint64_t max_message_bytes, int socket_buffer_bytes) {
  client::ConnectOptions o;
  o.client_name = client_name;
  o.auth_token = token;
  if (token_file) o.token_file = *token_file;
  o.connect_timeout = seconds_to_ms(connect_timeout, "connect_timeout");
  o.io_timeout = seconds_to_ms(io_timeout, "io_timeout");
  o.max_message_bytes = max_message_bytes;
  o.socket_buffer_bytes = socket_buffer_bytes;
  const std::string where = url.value_or(default_url());
  auto c = std::make_unique<PyConnection>();
  c->io_timeout = o.io_timeout;
  c->conn.emplace(blocking(c->lock, [&] { return client::Connection::connect(where, o); }));
  return c;
}

client::SessionDesc session_desc(uint32_t width, uint32_t height, const std::string& pipeline,
                                 const py::object& channels, const py::object& parameters,
                                 const py::object& output_format, uint32_t max_in_flight, bool share_input) {
  client::SessionDesc d;
  d.width = width;
  d.height = height;
  d.pipeline = pipeline;
  d.output_format = parse_format(output_format, "output_format");
  d.max_in_flight = max_in_flight;
  d.share_input = share_input;
  if (py::isinstance<py::dict>(channels)) {
    for (auto item : py::reinterpret_borrow<py::dict>(channels)) {
      const std::string name = py::str(item.first);
      d.channel(channel_by_name(name).id, parse_format(item.second, "channel '" + name + "'"));
    }
  } else if (py::isinstance<py::str>(channels)) {
    throw py::type_error("channels: expected a dict {name: 'f32' | 'f16'} or a list of names, got a str");
  } else {
    for (auto name : channels) d.channel(channel_by_name(py::str(name)).id, Format::F32);
  }
  if (!parameters.is_none()) {
    for (auto item : py::reinterpret_borrow<py::dict>(parameters)) {
      const std::string name = py::str(item.first);
      double value = 0.0;
      try {
        value = item.second.cast<double>();
      } catch (const py::cast_error&) {
        throw client::Error::usage(protocol::ErrorCode::InvalidParameter, "OPEN_SESSION.parameters",
                                   "parameter '" + name + "': " + std::string(py::repr(item.second)) +
                                       " is not a number");
      }
      d.parameter(name, value);
    }
  }
  return d;
}

FrameOptions frame_options(py::object view, py::object projection, py::object jitter, bool reset,
                           std::optional<uint64_t> frame_index, std::string motion, bool no_output,
                           py::object prev_view, py::object prev_projection, py::object prev_jitter) {
  FrameOptions o;
  o.view = std::move(view);
  o.projection = std::move(projection);
  o.jitter = std::move(jitter);
  o.reset = reset;
  o.frame_index = frame_index;
  o.motion = std::move(motion);
  o.no_output = no_output;
  o.prev_view = std::move(prev_view);
  o.prev_projection = std::move(prev_projection);
  o.prev_jitter = std::move(prev_jitter);
  return o;
}

std::string describe_parameter(const protocol::ParameterInfo& p) {
  return "<dn.ParameterInfo " + p.name + " default " + client::format_value(p.default_value) + " in " +
         client::format_range(p) + (p.integer ? ", integer" : "") + ">";
}

// submit() and denoise(): the frame and its options made into a FrameInput,
// then `send` (which blocks without the GIL).
template <class Send>
auto frame_method(Send send) {
  return [send](PySession& s, py::handle frame, py::object view, py::object projection, py::object jitter, bool reset,
                std::optional<uint64_t> frame_index, std::string motion, bool no_output, py::object prev_view,
                py::object prev_projection, py::object prev_jitter) {
    client::Session& session = s.get();
    const PreparedFrame f = prepare_frame(session, frame,
                                          frame_options(view, projection, jitter, reset, frame_index, motion, no_output,
                                                        prev_view, prev_projection, prev_jitter));
    return send(s, session, f);
  };
}

// The keyword arguments submit() and denoise() share.
#define DN_FRAME_KWARGS                                                                                           \
  py::kw_only(), py::arg("view") = py::none(), py::arg("projection") = py::none(), py::arg("jitter") = py::none(), \
      py::arg("reset") = false, py::arg("frame_index") = py::none(), py::arg("motion") = "to-previous",            \
      py::arg("no_output") = false, py::arg("prev_view") = py::none(), py::arg("prev_projection") = py::none(),    \
      py::arg("prev_jitter") = py::none()

}  // namespace

void bind_connection(py::module_& m) {
  m.attr("DEFAULT_SERVER_URL") = client::kDefaultServerUrl;
  m.attr("PROTOCOL_VERSION") = py::make_tuple(protocol::kVersionMajor, protocol::kVersionMinor);
  m.attr("__version__") = client::kClientVersion;

  py::class_<protocol::ParameterInfo>(m, "ParameterInfo", "One tunable of a pipeline, as the server announces it.")
      .def_readonly("name", &protocol::ParameterInfo::name)
      .def_readonly("default", &protocol::ParameterInfo::default_value)
      .def_readonly("min", &protocol::ParameterInfo::min_value)
      .def_readonly("max", &protocol::ParameterInfo::max_value)
      .def_readonly("integer", &protocol::ParameterInfo::integer)
      .def_readonly("description", &protocol::ParameterInfo::description)
      .def("__repr__", &describe_parameter);

  py::class_<protocol::PipelineInfo>(m, "PipelineInfo",
                                     "A pipeline the server offers: name, required and optional channel names, "
                                     "parameters (empty from a protocol 1.0 server).")
      .def_readonly("name", &protocol::PipelineInfo::name)
      .def_property_readonly("required", [](const protocol::PipelineInfo& p) { return channel_names(p.required_channels); })
      .def_property_readonly("optional", [](const protocol::PipelineInfo& p) { return channel_names(p.optional_channels); })
      .def_readonly("parameters", &protocol::PipelineInfo::parameters)
      .def("__repr__", [](const protocol::PipelineInfo& p) {
        return "<dn.PipelineInfo " + p.name + " requires " + std::string(py::str(channel_names(p.required_channels))) + ">";
      });

  py::class_<PySession>(m, "Session",
                        "One camera stream on the server (Connection.open_session). Use it as a context manager "
                        "to close it.")
      .def_property_readonly("id", [](PySession& s) { return s.get().id(); })
      .def_property_readonly("width", [](PySession& s) { return s.get().width(); })
      .def_property_readonly("height", [](PySession& s) { return s.get().height(); })
      .def_property_readonly("pipeline", [](PySession& s) { return s.get().info().pipeline; },
                             "The pipeline the session runs: for 'auto', the server's choice.")
      .def_property_readonly("pipeline_reason",
                             [](PySession& s) { return s.get().info().pipeline_reason.value_or(""); },
                             "For a session opened as 'auto': why the server chose `pipeline` ('' otherwise).")
      .def_property_readonly("output_format", [](PySession& s) { return format_name(s.get().info().output_format); })
      .def_property_readonly("channels",
                             [](PySession& s) {
                               py::dict d;
                               for (const auto& c : s.get().info().channels)
                                 d[py::str(channel_name(c.id))] = format_name(c.format);
                               return d;
                             })
      .def_property_readonly("device_bytes", [](PySession& s) { return s.get().info().device_bytes; })
      .def_property_readonly("watch_key", [](PySession& s) { return s.get().watch_key(); },
                             "the key a watcher needs (Connection.attach); empty from a server older than 1.6")
      .def_property_readonly("watch_command", [](PySession& s) { return s.get().watch_command(); },
                             "'DN_WATCH_KEY=KEY dn watch --server URL --session ID', ready to paste (the key stays off the command line)")
      .def_property_readonly("max_in_flight", [](PySession& s) { return s.get().max_in_flight(); })
      .def_property_readonly("in_flight",
                             [](PySession& s) {
                               client::Session& session = s.get();
                               return blocking(s.lock, [&] { return session.in_flight(); });
                             },
                             "frames submitted and not yet returned by wait()/poll()")
      .def_property_readonly("is_open", [](PySession& s) { return s.session && s.session->is_open(); })
      .def("submit", frame_method([](PySession& s, client::Session& session, const PreparedFrame& f) {
             return blocking(s.lock, [&] { return session.submit(f.input); });
           }),
           py::arg("frame"), DN_FRAME_KWARGS,
           "Sends a frame (dict channel name -> array, or a dn.Frame) and returns its frame index; blocks while "
           "max_in_flight frames are unanswered. Collect results in order with wait() or poll().")
      .def(
          "wait", [](PySession& s) { return to_python(blocking(s.lock, [&] { return s.get().wait(); })); },
          "The next result in submission order (blocks). A frame the server rejected raises its dn.ServerError "
          "here; the session stays usable.")
      .def(
          "poll",
          [](PySession& s) -> py::object {
            std::optional<client::Result> r = blocking(s.lock, [&] { return s.get().poll(); });
            if (!r) return py::none();
            return py::cast(to_python(*r));
          },
          "The next result if it has already arrived, else None; never blocks.")
      .def("denoise", frame_method([](PySession& s, client::Session& session, const PreparedFrame& f) {
             return to_python(blocking(s.lock, [&] { return session.denoise(f.input); })).image;
           }),
           py::arg("frame"), DN_FRAME_KWARGS,
           "submit() + wait(): the denoised image, (height, width, 3) float32 (None with no_output=True).")
      .def(
          "close",
          [](PySession& s) -> py::object {
            if (!s.session || !s.session->is_open()) return py::none();
            const protocol::SessionClosed c = blocking(s.lock, [&] { return s.session->close(); });
            return py::int_(c.frames_processed);
          },
          "CLOSE_SESSION: results not yet collected are discarded. Returns the frames the server processed "
          "(None if already closed).")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__",
           [](PySession& s, py::handle type, py::handle, py::handle) {
             if (!s.session || !s.session->is_open()) return false;
             try {
               blocking(s.lock, [&] { s.session->close(); });
             } catch (const client::Error&) {
               if (type.is_none()) throw;  // an exception from the block wins over a failing close
             }
             return false;
           })
      .def("__repr__", [](PySession& s) {
        if (!s.session) return std::string("<dn.Session closed>");
        return "<dn.Session " + std::to_string(s.session->id()) + " " + s.session->info().pipeline + " " +
               std::to_string(s.session->width()) + "x" + std::to_string(s.session->height()) +
               (s.session->is_open() ? "" : " closed") + ">";
      });

  py::class_<PyConnection>(m, "Connection", "A connection to dnserver (dn.connect). Use it as a context manager.")
      .def_property_readonly("endpoint", [](PyConnection& c) { return c.get().endpoint(); })
      .def_property_readonly("server_version", [](PyConnection& c) { return c.get().welcome().server_version; })
      .def_property_readonly("device_name", [](PyConnection& c) { return c.get().welcome().device_name; })
      .def_property_readonly("protocol_version",
                             [](PyConnection& c) { return py::make_tuple(protocol::kVersionMajor, c.get().protocol_minor()); },
                             "the version both sides speak: (1, min(server's minor, this library's))")
      .def_property_readonly("limits",
                             [](PyConnection& c) {
                               const protocol::Limits& l = c.get().welcome().limits;
                               py::dict d;
                               d["max_message_bytes"] = l.max_message_bytes;
                               d["max_session_bytes"] = l.max_session_bytes;
                               d["max_sessions"] = l.max_sessions;
                               d["max_width"] = l.max_width;
                               d["max_height"] = l.max_height;
                               d["max_frames_in_flight"] = l.max_frames_in_flight;
                               return d;
                             })
      .def_property_readonly("has_parameters", [](PyConnection& c) { return c.get().welcome().has_parameters; })
      .def_property_readonly("is_open", [](PyConnection& c) { return c.conn && c.conn->is_open(); })
      .def(
          "pipelines", [](PyConnection& c) { return c.get().welcome().pipelines; },
          "Every pipeline the server offers (dn.PipelineInfo: channels and parameter table), from WELCOME.")
      .def(
          "find_pipeline",
          [](PyConnection& c, const std::string& name) -> py::object {
            const protocol::PipelineInfo* p = c.get().find_pipeline(name);
            return p ? py::cast(*p) : py::none();
          },
          py::arg("name"), "The named pipeline's dn.PipelineInfo, or None.")
      .def(
          "ping",
          [](PyConnection& c) {
            client::Connection& conn = c.get();
            return blocking(c.lock, [&] { return conn.ping().count(); });
          },
          "PING -> PONG round trip in milliseconds.")
      .def(
          "stats",
          [](PyConnection& c) {
            client::Connection& conn = c.get();
            const protocol::Stats s = blocking(c.lock, [&] { return conn.stats(); });
            py::dict d;
            for (const auto& v : s.values) d[py::str(v.name)] = v.value;
            return d;
          },
          "The server's STATS as a dict name -> value.")
      .def(
          "open_session",
          [](PyConnection& c, uint32_t width, uint32_t height, const std::string& pipeline, py::object channels,
             py::object parameters, py::object output_format, uint32_t max_in_flight, bool share_input) {
            client::Connection& conn = c.get();
            const client::SessionDesc desc =
                session_desc(width, height, pipeline, channels, parameters, output_format, max_in_flight,
                             share_input);
            auto s = std::make_unique<PySession>();
            s->lock = c.lock;
            s->session.emplace(blocking(c.lock, [&] { return conn.open_session(desc); }));
            return s;
          },
          py::arg("width"), py::arg("height"), py::arg("pipeline") = protocol::kAutoPipeline, py::kw_only(),
          py::arg("channels") = py::make_tuple("radiance", "albedo", "normal", "depth", "motion"),
          py::arg("parameters") = py::none(), py::arg("output_format") = "f32", py::arg("max_in_flight") = 0,
          py::arg("share_input") = false,
          "OPEN_SESSION. pipeline: a name from Connection.pipelines, or 'auto' (the server chooses from the "
          "channels; protocol 1.10). channels: {name: 'f32' | 'f16'} (the wire format; arrays of the other type are converted) "
          "or a list of names (f32). parameters: {name: value}, checked against the server's table before "
          "anything is sent. max_in_flight: 0 = the server's limit. share_input: watchers' results also carry the "
          "noisy radiance (Result.input; protocol 1.7).")
      .def(
          "attach",
          [](PyConnection& c, uint64_t session_id, const std::string& watch_key) {
            client::Connection& conn = c.get();
            auto w = std::make_unique<PyWatcher>();
            w->lock = c.lock;
            w->endpoint = conn.endpoint();
            w->io_timeout = c.io_timeout;
            w->watcher.emplace(blocking(c.lock, [&] { return conn.attach(session_id, watch_key); }));
            return w;
          },
          py::arg("session_id"), py::arg("watch_key"),
          "ATTACH: a read-only dn.Watcher of another client's session, given its id and watch key.")
      .def(
          "watch",
          [](py::object self, uint64_t session_id, const std::string& watch_key) {
            return self.attr("attach")(session_id, watch_key);
          },
          py::arg("session_id"), py::arg("watch_key"), "Same as attach().")
      .def(
          "close",
          [](PyConnection& c) {
            if (c.conn) blocking(c.lock, [&] { c.conn->close(); });
          },
          "Closes the socket; sessions and watchers of this connection raise TransportError afterwards.")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__",
           [](PyConnection& c, py::handle, py::handle, py::handle) {
             if (c.conn) blocking(c.lock, [&] { c.conn->close(); });
             return false;
           })
      .def("__repr__", [](PyConnection& c) {
        if (!c.conn) return std::string("<dn.Connection closed>");
        return "<dn.Connection " + c.conn->endpoint() + " " + c.conn->welcome().device_name +
               (c.conn->is_open() ? "" : " closed") + ">";
      });

  m.def("connect", &connect, py::arg("url") = py::none(), py::kw_only(), py::arg("token") = py::none(),
        py::arg("token_file") = py::none(), py::arg("client_name") = "dn-python", py::arg("connect_timeout") = 10.0,
        py::arg("io_timeout") = 120.0, py::arg("max_message_bytes") = 0, py::arg("socket_buffer_bytes") = 8 << 20,
        "Connects to dnserver and does the handshake. url: 'tcp://HOST:PORT' or 'unix:///path'; None: $DN_SERVER, "
        "else dn.DEFAULT_SERVER_URL. token: the auth token (default: token_file, $DN_TOKEN, $DN_TOKEN_FILE). "
        "Timeouts in seconds (io_timeout 0 = forever).");
}

}  // namespace dn::python
