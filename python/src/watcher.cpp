// dn.Watcher: a read-only view of another client's session
// (Connection.attach), mirroring dn::client::Watcher; iterating it yields
// the newest result each time one arrives, until the session ends.
#include <algorithm>
#include <chrono>

#include "common.hpp"

namespace dn::python {

PyWatcher::~PyWatcher() {
  std::lock_guard<std::mutex> guard(*lock);
  watcher.reset();
}

namespace {

client::Watcher& get(PyWatcher& w) {
  if (!w.watcher) throw client::Error::usage("the watcher was closed");
  return *w.watcher;
}

// A wait without limit (io_timeout 0), in pieces next_for can take.
constexpr std::chrono::milliseconds kForever = std::chrono::hours(24);

// next() with the end of the stream told apart: nullopt when the session
// ended normally (SESSION_CLOSED) or, with `timed_out` set, when nothing
// arrived within the timeout (none: the connection's io_timeout, then a
// Transport error as Watcher::next() throws; io_timeout 0: forever).
std::optional<client::Result> next_or_end(PyWatcher& w, std::optional<double> timeout_s, bool& timed_out) {
  client::Watcher& watcher = get(w);
  timed_out = false;
  std::optional<std::chrono::milliseconds> limit;
  if (timeout_s) limit = std::chrono::milliseconds(static_cast<long long>(std::max(0.0, *timeout_s) * 1000.0 + 0.5));
  else if (w.io_timeout.count() > 0) limit = w.io_timeout;
  try {
    std::optional<client::Result> r = blocking(w.lock, [&]() -> std::optional<client::Result> {
      for (;;) {
        if (auto r = watcher.next_for(limit ? *limit : kForever)) return r;
        if (limit) return std::nullopt;
      }
    });
    if (!r) {
      timed_out = true;
      if (!timeout_s)
        throw client::Error::transport(w.endpoint,
                                       "timed out after " + std::to_string(limit->count()) +
                                           " ms waiting for a RESULT of session " + std::to_string(watcher.session_id()),
                                       protocol::ErrorCode::Timeout);
    }
    return r;
  } catch (const client::Error&) {
    if (watcher.closed()) {
      w.ended = true;
      return std::nullopt;
    }
    throw;
  }
}

}  // namespace

void bind_watcher(py::module_& m) {
  py::class_<PyWatcher>(m, "Watcher",
                        "A read-only view of a session (Connection.attach). Iterate it for each newest result "
                        "until the session ends; a watcher cares only about the newest frame, older ones that "
                        "arrived meanwhile are skipped (dropped counts them).")
      .def_property_readonly("session_id", [](PyWatcher& w) { return get(w).session_id(); })
      .def_property_readonly("width", [](PyWatcher& w) { return get(w).info().width; })
      .def_property_readonly("height", [](PyWatcher& w) { return get(w).info().height; })
      .def_property_readonly("pipeline", [](PyWatcher& w) { return get(w).info().pipeline; })
      .def_property_readonly("dropped", [](PyWatcher& w) { return get(w).dropped(); })
      .def_property_readonly(
          "closed",
          [](PyWatcher& w) -> py::object {
            const auto& c = get(w).closed();
            if (!c) return py::none();
            return py::int_(c->frames_processed);
          },
          "after the session ended normally (its owner closed it or went away): the frames it processed; else None")
      .def(
          "next",
          [](PyWatcher& w, std::optional<double> timeout) -> py::object {
            if (w.ended) return py::none();
            bool timed_out = false;
            std::optional<client::Result> r = next_or_end(w, timeout, timed_out);
            if (!r) return py::none();
            return py::cast(to_python(*r));
          },
          py::arg("timeout") = py::none(),
          "The newest result, waiting for one (timeout in seconds; None: the connection's io_timeout, then "
          "dn.TimeoutError). Returns None when the timeout passed or the session has ended (see closed); raises "
          "dn.Error when the stream ended with an error or the connection failed.")
      .def(
          "try_next",
          [](PyWatcher& w) -> py::object {
            client::Watcher& watcher = get(w);
            std::optional<client::Result> r = blocking(w.lock, [&] { return watcher.try_next(); });
            if (!r) return py::none();
            return py::cast(to_python(*r));
          },
          "The newest result that has already arrived, else None; never blocks.")
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__",
           [](PyWatcher& w) {
             if (w.ended) throw py::stop_iteration();
             bool timed_out = false;
             std::optional<client::Result> r = next_or_end(w, std::nullopt, timed_out);
             if (!r) throw py::stop_iteration();
             return to_python(*r);
           })
      .def(
          "close",
          [](PyWatcher& w) {
            py::gil_scoped_release release;
            std::lock_guard<std::mutex> guard(*w.lock);
            w.watcher.reset();
          },
          "Stops watching (later results of the session are dropped on arrival).")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__",
           [](PyWatcher& w, py::handle, py::handle, py::handle) {
             py::gil_scoped_release release;
             std::lock_guard<std::mutex> guard(*w.lock);
             w.watcher.reset();
             return false;
           })
      .def("__repr__", [](PyWatcher& w) {
        if (!w.watcher) return std::string("<dn.Watcher closed>");
        return "<dn.Watcher of session " + std::to_string(w.watcher->session_id()) + ">";
      });
}

}  // namespace dn::python
