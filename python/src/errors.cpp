// dn.Error and its subclasses, one per dn::client::ErrorKind, and the
// translation of the C++ exceptions the module can meet into them.
//
//   dn.Error (RuntimeError)           every dn::client::Error: .kind .code .field .server_message .endpoint
//     dn.ServerError                  the server answered ERROR
//     dn.TransportError               cannot connect, connection lost, timeout
//       dn.TimeoutError (+ TimeoutError)
//     dn.ProtocolError                the server sent something undecodable
//     dn.UsageError (+ ValueError)    rejected locally, nothing sent (bad URL, wrong shape, unknown parameter)
//   dn.ImageError (OSError)           an EXR that cannot be read or written
//   dn.ChannelMapError (ValueError)   dn.read_frame: a pass the pipeline needs is not in the file
#include <Python.h>

#include "common.hpp"
#include "camera_recovery.hpp"  // dn::cli::CameraRecoveryError (client/tools)
#include "dn/image/exr_io.hpp"
#include "presets.hpp"          // dn::cli::ChannelMapError (client/tools)

namespace dn::python {

namespace {

struct Classes {
  PyObject* error = nullptr;
  PyObject* server = nullptr;
  PyObject* transport = nullptr;
  PyObject* timeout = nullptr;
  PyObject* protocol = nullptr;
  PyObject* usage = nullptr;
  PyObject* image = nullptr;
  PyObject* channel_map = nullptr;
};
Classes classes;  // owned references, kept for the life of the process (as the module keeps them)

PyObject* make_class(py::module_& m, const char* name, const char* doc, std::initializer_list<PyObject*> bases) {
  const std::string qualified = std::string("dn.") + name;
  py::tuple base_tuple(bases.size());
  size_t i = 0;
  for (PyObject* b : bases) base_tuple[i++] = py::reinterpret_borrow<py::object>(b);
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base_tuple.ptr(), nullptr);
  if (!cls) throw py::error_already_set();
  m.add_object(name, py::reinterpret_borrow<py::object>(cls));
  return cls;  // the new reference is kept in `classes`
}

const char* kind_name(client::ErrorKind k) {
  switch (k) {
    case client::ErrorKind::Server: return "server";
    case client::ErrorKind::Transport: return "transport";
    case client::ErrorKind::Protocol: return "protocol";
    case client::ErrorKind::Usage: return "usage";
  }
  return "unknown";
}

void raise(const client::Error& e) {
  PyObject* cls = classes.error;
  switch (e.kind()) {
    case client::ErrorKind::Server: cls = classes.server; break;
    case client::ErrorKind::Transport: cls = e.is_timeout() ? classes.timeout : classes.transport; break;
    case client::ErrorKind::Protocol: cls = classes.protocol; break;
    case client::ErrorKind::Usage: cls = classes.usage; break;
  }
  py::object instance = py::reinterpret_borrow<py::object>(cls)(e.what());
  instance.attr("kind") = kind_name(e.kind());
  instance.attr("code") = client::code_name(e.code());
  instance.attr("field") = e.field();
  instance.attr("server_message") = e.server_message();
  instance.attr("endpoint") = e.endpoint();
  instance.attr("is_timeout") = e.is_timeout();
  PyErr_SetObject(cls, instance.ptr());
}

}  // namespace

void bind_errors(py::module_& m) {
  classes.error = make_class(m, "Error",
                             "An error of the dn client library (dn::client::Error). Attributes: kind ('server', "
                             "'transport', 'protocol', 'usage'), code (the protocol's error code name, e.g. "
                             "'InvalidChannel'), field (e.g. 'FRAME.planes[2]'), server_message, endpoint, is_timeout.",
                             {PyExc_RuntimeError});
  classes.server = make_class(m, "ServerError", "The server answered ERROR (code and field are the server's).",
                              {classes.error});
  classes.transport = make_class(m, "TransportError",
                                 "Cannot connect, the connection was closed or reset, or a reply timed out. The "
                                 "connection is unusable afterwards.",
                                 {classes.error});
  classes.timeout = make_class(m, "TimeoutError", "A TransportError for a reply that did not come in time.",
                               {classes.transport, PyExc_TimeoutError});
  classes.protocol = make_class(m, "ProtocolError", "The server sent bytes the client cannot decode.",
                                {classes.error});
  classes.usage = make_class(m, "UsageError",
                             "Rejected locally before anything was sent: a bad URL, an array of the wrong shape, a "
                             "channel that is unknown, undeclared or missing, an unknown parameter or a value out of "
                             "range. Also a ValueError.",
                             {classes.error, PyExc_ValueError});
  classes.image = make_class(m, "ImageError", "An image file that cannot be read or written, or lacks a channel.",
                             {PyExc_OSError});
  classes.channel_map = make_class(m, "ChannelMapError",
                                   "dn.read_frame: a channel the pipeline needs cannot be made from the file's "
                                   "passes, or its camera cannot be recovered; the message says which pass or "
                                   "setting is missing.",
                                   {PyExc_ValueError});

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const client::Error& e) {
      raise(e);
    } catch (const image::ImageError& e) {
      PyErr_SetString(classes.image, e.what());
    } catch (const cli::ChannelMapError& e) {
      PyErr_SetString(classes.channel_map, e.what());
    } catch (const cli::CameraRecoveryError& e) {
      PyErr_SetString(classes.channel_map, (e.reason() + "; " + cli::kPythonChannelSyntax.camera_hint()).c_str());
    }
  });
}

}  // namespace dn::python
