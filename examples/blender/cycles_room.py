"""Builds the project's Blender Cycles test scene from nothing and renders it.

    blender -b --factory-startup --python examples/blender/cycles_room.py -- \
        --out DIR [--width 320] [--height 180] [--frames 8] [--spp 1] [--seed 0] [--start 0]
        [--name frame] [--half] [--threads N] [--passes default|preset|denoising|all] [--still]

Writes DIR/frame_0000.exr, frame_0001.exr, ... (NAME_%04d.exr; frame numbers --start ..
--start+frames-1): one multilayer OpenEXR per frame (ZIP, full float unless
--half), view layer "ViewLayer". --passes picks the passes:

  default    Blender's defaults for a new view layer: Combined and Depth only,
             what a user who never opened the Passes panel has
  preset     the passes `dn denoise --preset cycles` reads when Denoising Data
             is absent, and no more: Combined, Depth, Normal, Position,
             Vector, Diffuse / Glossy / Transmission Direct, Indirect and
             Color, Emission, Environment, Volume Direct and Indirect
             (Blender's defaults otherwise: no Denoising Data, no AOVs)
  denoising  preset + Denoising Data (Denoising Albedo / Normal / Depth)
  all        (default) denoising + Mist + two shader AOVs: "Roughness"
             (value) and "SpecularF0" (colour)

The passes change only what is written, not the render: Combined is the
same for every --passes value, up to Cycles' run-to-run float noise (two
runs with the same settings differ as much). Read the files with
`dn denoise --preset cycles --input 'DIR/frame_%04d.exr'`. --still holds the
camera at its pose of frame --start: the frames differ only in noise (and the
Vector pass is 0), what a viewport accumulating samples shows.

The scene: a small room (diffuse walls, floor and ceiling; the wall behind
the camera is open to a dim grey world), a mirror sphere (metal, roughness 0),
a gold sphere (metal, roughness 0.2), a glossy floor whose roughness a checker
texture maps between 0.05 and 0.5, a small area light near the ceiling (a
small bright highlight in the mirror sphere) and a camera that pans and
dollies over the frames (linear keys, extrapolated, so the Vector pass of the
first and last frames carries the same motion as the others).

Sampling: Cycles on the CPU, --spp samples per pixel, adaptive sampling,
denoising and motion blur off (the Vector pass needs motion blur off), the
default pixel filter and clamping. The seed is animated: frame f renders
with Cycles' hash of (f, --seed), so frames have independent noise and two
runs with different --seed values are independent renders of the same
frames (a second reference for noise-corrected errors).
"""

import argparse
import math
import os
import sys
import time

import bpy


PASS_SETS = ("default", "preset", "denoising", "all")

# Data and light passes the cycles preset reads (client/tools/presets.cpp, p.settings).
PRESET_PASSES = ("combined", "z", "normal", "position", "vector", "diffuse_direct", "diffuse_indirect",
                 "diffuse_color", "glossy_direct", "glossy_indirect", "glossy_color", "transmission_direct",
                 "transmission_indirect", "transmission_color", "emit", "environment")


def parse_args(prog="cycles_room", doc=__doc__):
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog=prog + ".py", description=doc.split("\n")[0])
    p.add_argument("--out", required=True, help="output directory (frame_%%04d.exr)")
    p.add_argument("--width", type=int, default=320)
    p.add_argument("--height", type=int, default=180)
    p.add_argument("--frames", type=int, default=8)
    p.add_argument("--spp", type=int, default=1, help="Cycles samples per pixel")
    p.add_argument("--seed", type=int, default=0, help="Cycles seed (animated per frame)")
    p.add_argument("--start", type=int, default=0, help="first frame number")
    p.add_argument("--name", default="frame", help="file name prefix: DIR/NAME_%%04d.exr")
    p.add_argument("--half", action="store_true", help="half-float EXR instead of full float")
    p.add_argument("--threads", type=int, default=0, help="render threads (0 = all cores)")
    p.add_argument("--passes", choices=PASS_SETS, default="all",
                   help="default: Combined and Depth (Blender's defaults); preset: what --preset cycles reads without "
                        "Denoising Data; denoising: + Denoising Data; "
                        "all: + Denoising Data, Mist and the Roughness / SpecularF0 AOVs")
    p.add_argument("--still", action="store_true",
                   help="hold the camera at its pose of frame --start (the frames differ only in noise)")
    a = p.parse_args(argv)
    if a.width < 1 or a.height < 1 or a.frames < 1 or a.spp < 1:
        p.error("--width, --height, --frames and --spp must be >= 1")
    return a


# --- materials -------------------------------------------------------------


def new_material(name):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nt = m.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    return m, nt


def set_aov_name(node, name):
    # Blender >= 4.0: aov_name; 3.x: the node's "name" property is the AOV name.
    if hasattr(node, "aov_name"):
        node.aov_name = name
    else:
        node.name = name


def add_aovs(nt, roughness_socket_or_value, f0):
    """AOV outputs "Roughness" (value) and "SpecularF0" (colour)."""
    r = nt.nodes.new("ShaderNodeOutputAOV")
    set_aov_name(r, "Roughness")
    if isinstance(roughness_socket_or_value, (int, float)):
        r.inputs["Value"].default_value = float(roughness_socket_or_value)
    else:
        nt.links.new(roughness_socket_or_value, r.inputs["Value"])
    c = nt.nodes.new("ShaderNodeOutputAOV")
    set_aov_name(c, "SpecularF0")
    c.inputs["Color"].default_value = (*f0, 1.0)


def principled(name, base, metallic, roughness, specular=0.5, roughness_socket=None, f0=None, **inputs):
    """Principled BSDF; `inputs`: other inputs by name with spaces as underscores (transmission=1.0, ior=1.45)."""
    m, nt = new_material(name)
    bsdf = nt.nodes.new("ShaderNodeBsdfPrincipled")
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    for key, value in inputs.items():
        sock = next(i for i in bsdf.inputs if i.identifier.lower() == key.lower() or
                    i.name.lower() == key.replace("_", " ").lower())
        sock.default_value = value
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Specular"].default_value = specular
    bsdf.inputs["Roughness"].default_value = roughness
    if roughness_socket is not None:
        nt.links.new(roughness_socket(nt), bsdf.inputs["Roughness"])
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    if f0 is None:  # dielectric F0 = 0.08 * specular, metal F0 = base colour
        f0 = base if metallic > 0.5 else (0.08 * specular,) * 3
    rough = roughness_socket(nt) if roughness_socket is not None else roughness
    add_aovs(nt, rough, f0)
    return m


def diffuse(name, colour):
    m, nt = new_material(name)
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    bsdf.inputs["Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    add_aovs(nt, 1.0, (0.0, 0.0, 0.0))
    return m


_floor_roughness = {}


def floor_roughness(nt):
    """Checker of 0.5 m squares (object space) -> roughness 0.05 / 0.5; one node per tree."""
    key = nt.as_pointer()
    if key not in _floor_roughness:
        coord = nt.nodes.new("ShaderNodeTexCoord")
        checker = nt.nodes.new("ShaderNodeTexChecker")
        checker.inputs["Scale"].default_value = 2.0
        nt.links.new(coord.outputs["Object"], checker.inputs["Vector"])
        remap = nt.nodes.new("ShaderNodeMapRange")
        remap.inputs["From Min"].default_value = 0.0
        remap.inputs["From Max"].default_value = 1.0
        remap.inputs["To Min"].default_value = 0.05
        remap.inputs["To Max"].default_value = 0.5
        nt.links.new(checker.outputs["Fac"], remap.inputs["Value"])
        _floor_roughness[key] = remap.outputs["Result"]
    return _floor_roughness[key]


# --- geometry --------------------------------------------------------------


def plane(name, size, location, rotation, material):
    bpy.ops.mesh.primitive_plane_add(size=1.0, location=location, rotation=rotation)
    o = bpy.context.active_object
    o.name = name
    o.scale = (size[0], size[1], 1.0)
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)  # object space = metres
    o.data.materials.append(material)
    return o


def sphere(name, radius, location, material):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, radius=radius, location=location)
    o = bpy.context.active_object
    o.name = name
    bpy.ops.object.shade_smooth()
    o.data.materials.append(material)
    return o


def build_scene(a):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene

    # Room: x in [-2.5, 2.5], y in [-3, 3], z in [0, 2.8]; the wall at y = -3
    # (behind the camera) is open.
    W, D, H = 5.0, 6.0, 2.8
    white = diffuse("wall_white", (0.7, 0.7, 0.68))
    red = diffuse("wall_red", (0.65, 0.12, 0.1))
    green = diffuse("wall_green", (0.15, 0.5, 0.15))
    floor = principled("floor_glossy", (0.25, 0.24, 0.22), 0.0, 0.3, specular=0.5, roughness_socket=floor_roughness)
    plane("floor", (W, D), (0, 0, 0), (0, 0, 0), floor)
    plane("ceiling", (W, D), (0, 0, H), (math.pi, 0, 0), white)
    plane("wall_back", (W, H), (0, D / 2, H / 2), (math.pi / 2, 0, 0), white)
    plane("wall_left", (D, H), (-W / 2, 0, H / 2), (math.pi / 2, 0, math.pi / 2), red)
    plane("wall_right", (D, H), (W / 2, 0, H / 2), (math.pi / 2, 0, -math.pi / 2), green)

    mirror = principled("mirror", (0.95, 0.95, 0.95), 1.0, 0.0)
    gold = principled("gold", (1.0, 0.766, 0.336), 1.0, 0.2)
    sphere("mirror_sphere", 0.6, (-0.8, 1.2, 0.6), mirror)
    sphere("gold_sphere", 0.5, (0.9, 0.6, 0.5), gold)

    # Small area light near the ceiling, pointing down.
    light_data = bpy.data.lights.new("area", type="AREA")
    light_data.shape = "SQUARE"
    light_data.size = 0.5
    light_data.energy = 200.0
    light = bpy.data.objects.new("area", light_data)
    light.location = (0.3, 0.4, H - 0.05)
    scene.collection.objects.link(light)

    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.4, 0.45, 0.5, 1.0)
    bg.inputs["Strength"].default_value = 0.5
    scene.world = world

    # Camera: pans right-to-left and dollies in over the frames.
    cam_data = bpy.data.cameras.new("camera")
    cam_data.lens = 24.0
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    # Keys at --start and --start + 11 (extrapolated linearly), so the motion
    # per frame does not depend on --frames.
    cam.location = (0.6, -2.6, 1.3)
    cam.rotation_euler = (math.radians(80), 0, math.radians(8))
    cam.keyframe_insert("location", frame=a.start)
    cam.keyframe_insert("rotation_euler", frame=a.start)
    cam.location = (-0.2, -1.9, 1.2)
    cam.rotation_euler = (math.radians(82), 0, math.radians(-6))
    cam.keyframe_insert("location", frame=a.start + 11)
    cam.keyframe_insert("rotation_euler", frame=a.start + 11)
    for fc in cam.animation_data.action.fcurves:
        fc.extrapolation = "LINEAR"
        for k in fc.keyframe_points:
            k.interpolation = "LINEAR"
    scene.frame_start, scene.frame_end = a.start, a.start + a.frames - 1
    return scene


def configure(scene, a):
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = a.width, a.height, 100
    r.film_transparent = False
    r.use_motion_blur = False  # Cycles writes the Vector pass only without motion blur
    r.use_persistent_data = False
    if a.threads > 0:
        r.threads_mode, r.threads = "FIXED", a.threads
    c = scene.cycles
    c.device = "CPU"
    c.samples = a.spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.use_preview_denoising = False
    c.seed = a.seed
    c.use_animated_seed = True
    if hasattr(c, "use_light_tree"):  # Blender >= 3.5
        c.use_light_tree = False
    scene.view_settings.view_transform = "Standard"  # display only; EXR is linear

    r.image_settings.file_format = "OPEN_EXR_MULTILAYER"
    r.image_settings.color_depth = "16" if a.half else "32"
    r.image_settings.exr_codec = "ZIP"
    r.use_file_extension = True
    r.filepath = os.path.join(os.path.abspath(a.out), a.name + "_####")

    set_passes(scene, a.passes)


def set_passes(scene, passes):
    """The view layer's passes for --passes (set explicitly: no reliance on Blender's defaults)."""
    vl = scene.view_layers[0]
    vl.name = "ViewLayer"
    for p in PRESET_PASSES:
        setattr(vl, "use_pass_" + p, passes != "default" or p in ("combined", "z"))
    vl.cycles.use_pass_volume_direct = passes != "default"
    vl.cycles.use_pass_volume_indirect = passes != "default"
    vl.use_pass_mist = passes == "all"
    vl.cycles.denoising_store_passes = passes in ("denoising", "all")
    # The materials' AOV Output nodes write only AOVs the view layer declares.
    if passes == "all":
        for name, kind in (("Roughness", "VALUE"), ("SpecularF0", "COLOR")):
            aov = vl.aovs.add()
            aov.name, aov.type = name, kind
    scene.world.mist_settings.start, scene.world.mist_settings.depth = 0.5, 8.0


def hold_camera(scene, frame):
    """Fixes the camera at its animated pose of `frame` (its keys removed)."""
    scene.frame_set(frame)
    cam = scene.camera
    pose = cam.matrix_world.copy()
    cam.animation_data_clear()
    cam.matrix_world = pose


def run(prog, doc, build):
    """A scene script's main: options, build(a) -> scene, render settings and passes, render."""
    a = parse_args(prog, doc)
    os.makedirs(a.out, exist_ok=True)
    scene = build(a)
    if a.still:
        hold_camera(scene, a.start)
    configure(scene, a)
    t0 = time.time()
    bpy.ops.render.render(animation=True)
    total = time.time() - t0
    print(prog + ": %d frames %dx%d at %d spp (seed %d, passes %s%s) -> %s in %.2f s (%.3f s/frame), Blender %s" %
          (a.frames, a.width, a.height, a.spp, a.seed, a.passes, ", still" if a.still else "", a.out, total,
           total / a.frames,
           bpy.app.version_string))


if __name__ == "__main__":
    run("cycles_room", __doc__, build_scene)
