// Image files for scripts: EXR read/write through dn_imageio
// (dn/image/exr_io.hpp), the error metrics of dn/image/metrics.hpp, and
// dn.read_frame: one frame of a renderer's EXR through the `dn denoise`
// presets (client/tools/presets.hpp: dnrender, Blender Cycles), the same
// channel mapping, conversions and camera recovery as the CLI.
#include <numeric>

#include "camera_recovery.hpp"
#include "common.hpp"
#include "dn/image/exr_io.hpp"
#include "dn/image/metrics.hpp"
#include "frame_source.hpp"
#include "presets.hpp"
#include "reflection_features.hpp"
#include "statistics_kind.hpp"

namespace dn::python {

namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

FloatArray image_array(const std::vector<float>& data, int width, int height, uint32_t components) {
  std::vector<py::ssize_t> shape = {height, width};
  if (components != 1) shape.push_back(components);
  FloatArray a(shape);
  std::copy(data.begin(), data.end(), a.mutable_data());
  return a;
}

py::dict read_exr(const std::string& path) {
  std::map<std::string, std::vector<float>> data;
  int w = 0, h = 0;
  {
    py::gil_scoped_release release;
    image::ExrReader exr(path);
    w = exr.width();
    h = exr.height();
    for (const auto& name : exr.channels()) data[name] = exr.read_channel(name);
  }
  py::dict out;
  for (const auto& [name, values] : data) out[py::str(name)] = image_array(values, w, h, 1);
  return out;
}

FloatArray read_exr_rgb(const std::string& path) {
  int w = 0, h = 0;
  std::vector<float> rgb;
  {
    py::gil_scoped_release release;
    rgb = image::read_exr_rgb(path, w, h);
  }
  return image_array(rgb, w, h, 3);
}

FloatArray as_float(const py::handle& a, const std::string& what) {
  FloatArray f = FloatArray::ensure(a);
  if (!f) {
    PyErr_Clear();
    throw py::type_error(what + ": expected a float array");
  }
  return f;
}

void write_exr(const std::string& path, const py::object& image, bool half) {
  const image::ExrPixelType type = half ? image::ExrPixelType::Half : image::ExrPixelType::Float;
  std::vector<FloatArray> keep;
  std::vector<image::ExrChannelOut> channels;
  int w = -1, h = -1;
  auto add_image = [&](FloatArray a, const std::vector<std::string>& names, const std::string& what) {
    const size_t c = a.ndim() == 3 ? size_t(a.shape(2)) : 1;
    if (a.ndim() < 2 || a.ndim() > 3 || c != names.size())
      throw py::value_error(what + ": expected shape (height, width" +
                            (names.size() == 1 ? ")" : ", " + std::to_string(names.size()) + ")"));
    if (w >= 0 && (a.shape(0) != h || a.shape(1) != w))
      throw py::value_error(what + ": every channel must have the same height and width");
    h = int(a.shape(0));
    w = int(a.shape(1));
    for (size_t i = 0; i < names.size(); ++i) channels.push_back({names[i], a.data() + i, c, type});
    keep.push_back(std::move(a));
  };
  if (py::isinstance<py::dict>(image)) {
    for (auto item : py::reinterpret_borrow<py::dict>(image)) {
      const std::string name = py::str(item.first);
      add_image(as_float(item.second, "channel '" + name + "'"), {name}, "channel '" + name + "'");
    }
  } else {
    FloatArray a = as_float(image, "image");
    const py::ssize_t c = a.ndim() == 3 ? a.shape(2) : 1;
    if (c == 3) add_image(std::move(a), {"R", "G", "B"}, "image");
    else if (c == 4) add_image(std::move(a), {"R", "G", "B", "A"}, "image");
    else if (c == 1) add_image(std::move(a), {"Y"}, "image");
    else throw py::value_error("image: expected shape (height, width), (height, width, 3) or (height, width, 4)");
  }
  if (channels.empty()) throw py::value_error("write_exr: nothing to write");
  py::gil_scoped_release release;
  image::write_exr(path, w, h, channels);
}

std::pair<FloatArray, FloatArray> same_shape(const py::handle& a, const py::handle& ref) {
  FloatArray x = as_float(a, "a"), r = as_float(ref, "ref");
  bool same = x.ndim() == r.ndim();
  for (py::ssize_t i = 0; same && i < x.ndim(); ++i) same = x.shape(i) == r.shape(i);
  if (!same) throw py::value_error("a and ref must have the same shape");
  return {x, r};
}

// ---- dn.read_frame ------------------------------------------------------------------------------

LoadedFrame read_frame(const std::string& path, const py::object& pipeline_obj, const std::string& preset_name,
                       const std::optional<std::string>& layer, const py::object& channels_obj,
                       bool fp16, const py::object& view, const py::object& projection, const py::object& jitter,
                       const std::optional<std::string>& camera_file, long long number) {
  const protocol::PipelineInfo* pipeline = nullptr;
  if (!pipeline_obj.is_none()) {
    if (!py::isinstance<protocol::PipelineInfo>(pipeline_obj))
      throw py::type_error("pipeline: expected a dn.PipelineInfo (connection.find_pipeline(name)) or None");
    pipeline = &pipeline_obj.cast<const protocol::PipelineInfo&>();
  }
  std::optional<protocol::Mat4> given_view, given_projection;
  std::optional<std::array<float, 2>> given_jitter;
  if (!view.is_none() || !projection.is_none()) {
    if (view.is_none() || projection.is_none()) throw client::Error::usage("read_frame: view and projection go together");
    if (camera_file) throw client::Error::usage("read_frame: give either camera_file or view and projection");
    given_view = to_mat4(view, "view");
    given_projection = to_mat4(projection, "projection");
  }
  if (!jitter.is_none()) given_jitter = to_vec2(jitter, "jitter");
  // channels: a list of names (the preset's mapping for each) or a dict name -> SPEC (as `dn denoise
  // --channel NAME=SPEC` takes it) or None (the preset's); either way exactly these channels.
  std::optional<std::string> only_list;
  std::vector<std::string> assignments;
  if (!channels_obj.is_none()) {
    only_list.emplace();
    auto add_name = [&](const py::handle& name) {
      if (!py::isinstance<py::str>(name)) throw py::type_error("channels: expected protocol channel names (str)");
      *only_list += (only_list->empty() ? "" : ",") + std::string(py::str(name));
    };
    if (py::isinstance<py::dict>(channels_obj)) {
      for (auto item : py::reinterpret_borrow<py::dict>(channels_obj)) {
        add_name(item.first);
        if (item.second.is_none()) continue;
        if (!py::isinstance<py::str>(item.second))
          throw py::type_error("channels: a mapping's value is a SPEC string (e.g. 'ViewLayer.DiffCol') or None");
        assignments.push_back(std::string(py::str(item.first)) + "=" + std::string(py::str(item.second)));
      }
    } else if (py::isinstance<py::str>(channels_obj)) {
      throw py::type_error("channels: expected a list of names or a dict name -> SPEC, not a str");
    } else {
      for (auto name : channels_obj) add_name(name);
    }
  }

  struct Native {
    cli::Preset preset;
    std::vector<cli::ResolvedChannel> plan;
    std::optional<cli::RoughGuidePlan> rough;
    std::vector<protocol::Parameter> parameters;
    cli::LoadedFrame frame;
    std::string source;
    double residual = 0;
  } n;
  {
    py::gil_scoped_release release;
    image::ExrReader exr(path);
    n.preset = cli::make_preset(preset_name, exr.channels(), layer.value_or(""));
    std::optional<std::vector<protocol::ChannelId>> only;
    if (only_list) only = cli::parse_channel_list(*only_list, cli::kPythonChannelSyntax);
    std::vector<cli::ChannelSpec> overrides;
    for (const auto& a : assignments) overrides.push_back(cli::parse_channel_override(a, cli::kPythonChannelSyntax));
    n.plan = cli::plan_channels(n.preset, overrides, pipeline, only, exr.channels(), path, cli::kPythonChannelSyntax);
    n.rough = cli::plan_rough_guides(n.preset, n.plan, exr.channels());
    cli::apply_statistics_kind(exr.string_attribute("dn.stat_samples"), path, n.plan, pipeline, n.parameters);
    n.frame = cli::load_frame(exr, n.plan, number, n.rough ? &*n.rough : nullptr);
    // The camera: given > camera_file > the header's dn.* > recovered from the Position pass > identity.
    if (given_view) {
      n.frame.camera.view = given_view;
      n.frame.camera.projection = given_projection;
      n.frame.camera.prev_view.reset();
      n.frame.camera.prev_projection.reset();
      n.frame.camera.prev_jitter.reset();
    }
    if (given_jitter) n.frame.camera.jitter = given_jitter;
    // As with `dn denoise`: a camera is looked for only when the pipeline or a planned channel uses it.
    cli::FrameCameras cameras(camera_file.value_or(""), n.preset, exr.channels(),
                              cli::plan_needs_camera(pipeline, n.plan), cli::kPythonChannelSyntax);
    const cli::FrameCameras::Source source = cameras.apply(exr, number, n.frame.camera);
    n.source = given_view ? "given" : cli::to_string(source);
    if (auto rec = cameras.record(number)) n.residual = rec->rms_px;
    cli::apply_camera_conversions(n.frame, n.plan, exr, cli::kPythonChannelSyntax);
    if (n.rough) cli::apply_rough_guides(n.frame, *n.rough);
    cli::derive_reflection_features(n.frame, n.plan, exr, cli::kPythonChannelSyntax);
  }

  LoadedFrame out;
  out.path = path;
  out.preset = n.preset.name;
  out.width = n.frame.width;
  out.height = n.frame.height;
  for (const auto& p : n.frame.planes) {
    const protocol::ChannelInfo* ci = protocol::find_channel(p.id);
    out.planes[py::str(channel_name(p.id))] = image_array(p.data, out.width, out.height, ci ? ci->components : 1);
  }
  for (const auto& ch : n.plan) {
    const std::string name = channel_name(ch.id);
    out.channels[py::str(name)] = format_name(cli::wire_format(ch.id, fp16));
    std::string where = ch.describe();
    if (n.rough)
      for (const auto& r : n.rough->channels)
        if (r.id == ch.id) where += " where " + n.rough->describe_rule() + ", else " + r.describe();
    out.mapping[py::str(name)] = where;
  }
  for (const auto& p : n.parameters) out.parameters[py::str(p.name)] = p.value;
  out.view = n.frame.camera.view;
  out.projection = n.frame.camera.projection;
  out.jitter = n.frame.camera.jitter;
  out.prev_view = n.frame.camera.prev_view;
  out.prev_projection = n.frame.camera.prev_projection;
  out.prev_jitter = n.frame.camera.prev_jitter;
  out.camera_source = n.source;
  out.camera_residual_px = n.residual;
  return out;
}

py::object optional_mat4(const std::optional<protocol::Mat4>& m) { return m ? py::object(from_mat4(*m)) : py::none(); }
py::object optional_vec2(const std::optional<std::array<float, 2>>& v) {
  return v ? py::object(py::make_tuple((*v)[0], (*v)[1])) : py::none();
}

}  // namespace

void bind_image_io(py::module_& m) {
  m.def("read_exr", &read_exr, py::arg("path"),
        "Every channel of an EXR (part 0) as a dict name -> (height, width) float32 array, rows top-first "
        "(any pixel type is converted), e.g. 'ViewLayer.Combined.R'.");
  m.def("read_exr_rgb", &read_exr_rgb, py::arg("path"),
        "R, G, B (or, if absent, the first layer that has .R/.G/.B) as a (height, width, 3) float32 array.");
  m.def("write_exr", &write_exr, py::arg("path"), py::arg("image"), py::kw_only(), py::arg("half") = false,
        "Writes a (height, width, 3) array as R, G, B ((h, w, 4): R, G, B, A; (h, w): Y), or a dict "
        "name -> (height, width) array as those channels; ZIP-compressed, float (half=True: half).");
  m.def(
      "rmse",
      [](const py::handle& a, const py::handle& ref) {
        auto [x, r] = same_shape(a, ref);
        return image::rmse(x.data(), r.data(), size_t(x.size()));
      },
      py::arg("a"), py::arg("ref"), "sqrt(mean((a - ref)^2)) over every component (dn/image/metrics.hpp).");
  m.def(
      "relative_mse",
      [](const py::handle& a, const py::handle& ref, double eps) {
        auto [x, r] = same_shape(a, ref);
        return image::relative_mse(x.data(), r.data(), size_t(x.size()), eps);
      },
      py::arg("a"), py::arg("ref"), py::arg("eps") = 0.01,
      "mean((a - ref)^2 / (ref^2 + eps)) over every component, as `dn denoise -r` reports it.");

  py::class_<LoadedFrame>(m, "Frame",
                          "One frame read by dn.read_frame: planes (channel name -> array, ready for "
                          "Session.submit), channels (name -> wire format, ready for open_session), the camera, "
                          "and where each channel came from (mapping).")
      .def_readonly("path", &LoadedFrame::path)
      .def_readonly("preset", &LoadedFrame::preset)
      .def_readonly("width", &LoadedFrame::width)
      .def_readonly("height", &LoadedFrame::height)
      .def_readonly("planes", &LoadedFrame::planes)
      .def_readonly("channels", &LoadedFrame::channels)
      .def_readonly("parameters", &LoadedFrame::parameters,
                    "session parameters the file implies (dnrender's demodulated statistics); usually empty")
      .def_readonly("mapping", &LoadedFrame::mapping)
      .def_property_readonly("view", [](const LoadedFrame& f) { return optional_mat4(f.view); })
      .def_property_readonly("projection", [](const LoadedFrame& f) { return optional_mat4(f.projection); })
      .def_property_readonly("jitter", [](const LoadedFrame& f) { return optional_vec2(f.jitter); })
      .def_property_readonly("prev_view", [](const LoadedFrame& f) { return optional_mat4(f.prev_view); })
      .def_property_readonly("prev_projection", [](const LoadedFrame& f) { return optional_mat4(f.prev_projection); })
      .def_property_readonly("prev_jitter", [](const LoadedFrame& f) { return optional_vec2(f.prev_jitter); })
      .def_readonly("camera_source", &LoadedFrame::camera_source,
                    "'given', 'camera file', 'EXR header', 'Position pass' (recovered) or 'identity'")
      .def_readonly("camera_residual_px", &LoadedFrame::camera_residual_px,
                    "RMS reprojection residual of a camera recovered from the Position pass")
      .def("__repr__", [](const LoadedFrame& f) {
        return "<dn.Frame " + f.path + " " + std::to_string(f.width) + "x" + std::to_string(f.height) + " preset " +
               f.preset + ": " + std::string(py::str(py::list(f.planes.attr("keys")()))) + ">";
      });

  m.def("read_frame", &read_frame, py::arg("path"), py::arg("pipeline") = py::none(), py::kw_only(),
        py::arg("preset") = "auto", py::arg("layer") = py::none(), py::arg("channels") = py::none(),
        py::arg("fp16") = false, py::arg("view") = py::none(), py::arg("projection") = py::none(),
        py::arg("jitter") = py::none(), py::arg("camera_file") = py::none(), py::arg("number") = 0,
        "Reads one frame of a renderer's EXR as `dn denoise` does: preset 'cycles' (Blender multilayer EXR), "
        "'dnrender' or 'auto'; every channel `pipeline` (a dn.PipelineInfo) requires, and the optional ones the "
        "file has (channels: exactly these names, a list, or a dict name -> SPEC of `dn denoise --channel`, or None "
        "for the preset's); Cycles' depth, vector and Denoising Data conversions. The camera: "
        "view and projection if given, else camera_file (export_camera.py's format, line `frame <number>`), else "
        "the EXR header, else recovered from the Position pass. Raises dn.ChannelMapError naming the pass (and "
        "the Blender setting) when one is missing.");
}

}  // namespace dn::python
