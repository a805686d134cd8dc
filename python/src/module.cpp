// The `dn` Python module: a thin mirror of the dn::client library
// (docs/client.md, "Python bindings"). Each area binds itself:
// errors.cpp (dn.Error and subclasses), frames.cpp (NumPy <-> frames,
// dn.Result), connection.cpp (dn.connect, Connection, Session, pipelines),
// watcher.cpp (dn.Watcher), image_io.cpp (EXR files, metrics, dn.read_frame).
#include "common.hpp"

PYBIND11_MODULE(dn, m) {
  m.doc() =
      "dn: the Python client of dnserver, the denoising service (docs/client.md, \"Python bindings\").\n\n"
      "    import dn, numpy as np\n"
      "    with dn.connect('unix:///run/dn/dnserver.sock') as conn:\n"
      "        with conn.open_session(64, 36, 'svgf', channels={'radiance': 'f32', 'albedo': 'f16', 'normal': 'f16',\n"
      "                                                         'depth': 'f32', 'motion': 'f32'}) as s:\n"
      "            rgb = s.denoise({'radiance': radiance, 'albedo': albedo, ...})  # (36, 64, 3) float32\n";
  using namespace dn::python;
  bind_errors(m);
  bind_frames(m);
  bind_connection(m);
  bind_watcher(m);
  bind_image_io(m);
}
