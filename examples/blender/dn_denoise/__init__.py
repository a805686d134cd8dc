"""dn denoise: a Blender add-on that denoises the final render through a running dnserver.

Install the zip (build/python/dn_denoise_addon.zip, made by the build) with
Preferences > Add-ons > Install, and enable "Render: dn denoise". Its
preferences hold the server address (empty: $DN_SERVER, else
tcp://127.0.0.1:7878), the directory of the dn Python module (empty:
$DN_MODULE_DIR; Blender's Python does not read PYTHONPATH) and whether every
finished render is denoised. Properties > Render > "dn denoise" has its two
operators:

  Use the Passes dn Reads   Combined, Z, Normal, Diffuse Color and Denoising
                            Data (albedo, normal and depth as `dn denoise
                            --preset cycles` reads them); Cycles' own denoiser off
  Denoise Render            the Render Result, saved as a multilayer float EXR,
                            read as `dn denoise` reads it (dn.read_frame), sent to
                            a session of pipeline "auto": the server chooses from
                            the passes there are, and the result becomes the float
                            image "dn denoised", for an Image Editor or the
                            compositor's Image node

The choice and why are reported (Info) and kept on the image as the custom
properties "dn_pipeline" and "dn_reason".
"""

bl_info = {
    "name": "dn denoise",
    "author": "dn maintainers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > dn denoise",
    "description": "Denoises the final render through a running dnserver, which chooses the pipeline",
    "category": "Render",
}

import os
import shutil
import tempfile

import bpy
import numpy as np
from bpy.app.handlers import persistent

from .blender_image import to_blender_image
from .camera import camera_matrices
from .module import import_dn

# The passes the cycles preset reads for one finished frame (docs/client.md, "Preset cycles").
PASSES = ("combined", "z", "normal", "diffuse_color")


class DnPreferences(bpy.types.AddonPreferences):
    bl_idname = __name__

    server: bpy.props.StringProperty(
        name="Server", default="", description="dnserver address; empty: $DN_SERVER, else tcp://127.0.0.1:7878")
    module_dir: bpy.props.StringProperty(
        name="dn module directory", default="", subtype="DIR_PATH",
        description="directory holding the dn Python module (dn.cpython-*.so); empty: $DN_MODULE_DIR")
    after_render: bpy.props.BoolProperty(
        name="Denoise every finished render", default=True,
        description="run Denoise Render when a render completes (with a UI)")

    def draw(self, context):
        for name in ("server", "module_dir", "after_render"):
            self.layout.prop(self, name)


def preferences(context):
    return context.preferences.addons[__name__].preferences


def use_passes(scene, view_layer):
    for p in PASSES:
        setattr(view_layer, "use_pass_" + p, True)
    view_layer.cycles.denoising_store_passes = True
    scene.cycles.use_denoising = False  # the service denoises


def save_render(scene, path):
    """The Render Result, every pass, as a multilayer float EXR at `path`."""
    result = bpy.data.images.get("Render Result")
    if result is None:
        raise RuntimeError("there is no render to denoise: render first (F12)")
    settings = scene.render.image_settings
    kept = (settings.file_format, settings.color_depth, settings.exr_codec)
    try:
        settings.file_format = "OPEN_EXR_MULTILAYER"
        settings.color_depth = "32"
        settings.exr_codec = "ZIP"
        result.save_render(path, scene=scene)
    finally:
        settings.file_format, settings.color_depth, settings.exr_codec = kept
    if not os.path.exists(path):
        raise RuntimeError("the Render Result is empty: render first (F12)")


def denoise_render(context):
    """Denoises the Render Result; returns the image, the pipeline and the reason."""
    prefs = preferences(context)
    dn = import_dn([prefs.module_dir, os.environ.get("DN_MODULE_DIR")])  # ImportError: reported
    scene = context.scene
    folder = tempfile.mkdtemp(prefix="dn-addon-")
    try:
        path = os.path.join(folder, "render.exr")
        save_render(scene, path)
        try:
            view, projection = (np.array(m) for m in camera_matrices(scene))
        except ValueError:
            view = projection = None  # no perspective camera: read_frame says so only if the choice needs one
        conn = dn.connect(prefs.server or None, client_name="blender-dn_denoise")
        try:
            auto = conn.find_pipeline("auto")
            if auto is None:
                raise RuntimeError("%s cannot choose a pipeline (a server before protocol 1.10)" % conn.endpoint)
            frame = dn.read_frame(path, auto, preset="cycles", view=view, projection=projection)
            # One render is one frame: its motion (a Vector pass) moves no history, and auto would
            # choose a temporal pipeline for it.
            planes = {name: plane for name, plane in frame.planes.items() if name != "motion"}
            channels = {name: kind for name, kind in frame.channels.items() if name != "motion"}
            with conn.open_session(frame.width, frame.height, "auto", channels=channels,
                                   parameters=frame.parameters) as session:
                rgb = session.denoise(planes)
                pipeline, reason = session.pipeline, session.pipeline_reason
        finally:
            conn.close()
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    image = to_blender_image(rgb)
    image["dn_pipeline"], image["dn_reason"] = pipeline, reason
    return image, pipeline, reason


class DN_OT_denoise_render(bpy.types.Operator):
    """Denoise the Render Result through dnserver into the image "dn denoised\""""
    bl_idname = "dn.denoise_render"
    bl_label = "Denoise Render"

    def execute(self, context):
        try:
            image, pipeline, reason = denoise_render(context)
        except Exception as e:  # a connection, server or file error: reported, Blender goes on
            self.report({"ERROR"}, "dn denoise: %s" % e)
            return {"CANCELLED"}
        self.report({"INFO"}, "dn denoise: pipeline %s (%s) -> image '%s'" % (pipeline, reason, image.name))
        return {"FINISHED"}


class DN_OT_use_passes(bpy.types.Operator):
    """Turn on the passes dn reads (Combined, Z, Normal, Diffuse Color, Denoising Data)"""
    bl_idname = "dn.use_passes"
    bl_label = "Use the Passes dn Reads"

    def execute(self, context):
        use_passes(context.scene, context.view_layer)
        self.report({"INFO"}, "dn denoise: passes on: %s, Denoising Data" % ", ".join(PASSES))
        return {"FINISHED"}


class DN_PT_render(bpy.types.Panel):
    bl_label = "dn denoise"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"

    def draw(self, context):
        prefs = preferences(context)
        self.layout.prop(prefs, "server")
        self.layout.prop(prefs, "after_render")
        self.layout.operator(DN_OT_use_passes.bl_idname)
        self.layout.operator(DN_OT_denoise_render.bl_idname)


def denoise_once():
    bpy.ops.dn.denoise_render()
    return None  # a timer that runs once


@persistent
def after_render(scene, _depsgraph=None):
    # After the render job, on the main thread at the next event: the operator saves the finished result.
    if not bpy.app.background and preferences(bpy.context).after_render:
        bpy.app.timers.register(denoise_once, first_interval=0.0)


CLASSES = (DnPreferences, DN_OT_denoise_render, DN_OT_use_passes, DN_PT_render)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.app.handlers.render_complete.append(after_render)


def unregister():
    if after_render in bpy.app.handlers.render_complete:
        bpy.app.handlers.render_complete.remove(after_render)
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
