"""Renders frames with Cycles and denoises them through dnserver, from Blender's Python.

    blender -b scene.blend --python examples/blender/denoise_render.py -- \
        --server URL [--frames A..B] [--pipeline svgf] [--out DIR] [--dn-module-dir build/python]

or, with a UI, open the script in the Text Editor and Run Script (the options
then come from $DN_SERVER and the defaults): each denoised frame appears in an
Image Editor (the first one on the screen, else the largest 3D Viewport turns
into one) as the image "dn denoised".

For each frame it renders the scene to a multilayer EXR in a temporary
directory, reads it with dn.read_frame (the `cycles` preset of `dn denoise`,
docs/client.md "Preset cycles": which pass makes which channel, and the
depth, vector and Denoising Data conversions), sends it to the session with
the camera taken from Blender, and puts the result into a float image
(bpy.data.images, pixels set with foreach_set). Rendering frame N+1 overlaps
the server's work on frame N: frames are submitted, and results collected
as they arrive. In background mode (-b) every denoised frame is saved as
DIR/denoised_####.exr (float, linear, with dn.write_exr).

The passes it turns on (View Layer Properties > Passes), for the channels of
docs/client.md's table:
  Combined                  radiance (svgf and the other radiance-mode pipelines)
  Diffuse Color             albedo (the modulator Cycles divides its diffuse light passes by)
  Normal                    normal (world space, as Cycles writes it)
  Z                         depth (Cycles' background 1e10 becomes +inf)
  Vector                    motion (needs motion blur off, which it turns off)
  Emission, Environment     emission (not filtered, added back)
  Denoising Data            albedo and depth on mirrors (what a mirror shows)
  Position                  the camera when none is given (kept for `dn denoise` on the same files)
  Diffuse/Glossy Direct, Indirect, Color
                            the split-lighting channels of svgf-fb and reflect; those pipelines
                            also need the SpecularF0 and Roughness shader AOVs, which only the
                            scene's materials can write (cycles_room.py's add_aovs shows how)

The dn module is the one built in build/python (python/ in the repository):
Blender's Python does not read PYTHONPATH unless started with
--python-use-system-env, so give its directory with --dn-module-dir or
$DN_MODULE_DIR (the way for a run from the Text Editor), or leave the
default: build/python of this script's repository.
"""

import argparse
import os
import shutil
import sys
import tempfile
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__)) if "__file__" in globals() else os.getcwd()


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="denoise_render.py", description=__doc__.split("\n")[0])
    p.add_argument("--server", default=None, help="dnserver address (default: $DN_SERVER, else tcp://127.0.0.1:7878)")
    p.add_argument("--frames", default=None, help="A..B or A (default: the scene's current frame)")
    p.add_argument("--pipeline", default="svgf", help="denoising pipeline (default svgf)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="pipeline parameter")
    p.add_argument("--out", default=None, help="where denoised_####.exr go in background mode "
                   "(default: 'denoised' next to the .blend, or in the current directory)")
    p.add_argument("--renders", default=None, help="keep the rendered EXRs in this directory (default: a "
                   "temporary directory, removed at the end)")
    p.add_argument("--dn-module-dir", default=None, help="directory holding the dn module (default: $DN_MODULE_DIR, "
                   "else build/python of this repository)")
    p.add_argument("--width", type=int, help="override the render width (resolution percentage becomes 100)")
    p.add_argument("--height", type=int, help="override the render height")
    p.add_argument("--samples", type=int, help="override the Cycles samples per pixel")
    p.add_argument("--fp16", action="store_true", help="send fp16 planes (half the bytes)")
    return p.parse_args(argv)


def import_dn(module_dir):
    sys.path.insert(0, HERE)
    from dn_denoise.module import import_dn as import_from  # the add-on's, beside this script
    try:
        return import_from([module_dir or os.environ.get("DN_MODULE_DIR"),
                            os.path.join(HERE, "..", "..", "build", "python")])
    except ImportError as e:
        raise SystemExit("denoise_render.py: %s with --dn-module-dir" % e)


def frame_list(spec, scene):
    if not spec:
        return [scene.frame_current]
    a, sep, b = spec.partition("..")
    first, last = int(a), int(b) if sep else int(a)
    if last < first:
        raise SystemExit("denoise_render.py: --frames %s: the last frame is before the first" % spec)
    return list(range(first, last + 1))


def configure(scene, args):
    """Cycles, the passes the presets read, a multilayer float EXR per frame."""
    scene.render.engine = "CYCLES"
    if args.width or args.height:
        scene.render.resolution_x = args.width or scene.render.resolution_x
        scene.render.resolution_y = args.height or scene.render.resolution_y
        scene.render.resolution_percentage = 100
    if args.samples:
        scene.cycles.samples = args.samples
        scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False  # the service denoises
    scene.render.use_motion_blur = False  # Cycles writes the Vector pass only without it
    vl = bpy.context.view_layer
    for p in ("combined", "z", "normal", "vector", "position", "emit", "environment", "diffuse_direct",
              "diffuse_indirect", "diffuse_color", "glossy_direct", "glossy_indirect", "glossy_color"):
        setattr(vl, "use_pass_" + p, True)
    vl.cycles.denoising_store_passes = True
    settings = scene.render.image_settings
    settings.file_format = "OPEN_EXR_MULTILAYER"
    settings.color_depth = "32"  # half would break the exact Combined = sum of the light passes
    settings.exr_codec = "ZIP"
    scene.render.use_file_extension = True


def show(dn_image):
    """Shows the image in an Image Editor; False without a UI."""
    if bpy.app.background or not bpy.context.window_manager.windows:
        return False
    areas = [a for w in bpy.context.window_manager.windows for a in w.screen.areas]
    editors = [a for a in areas if a.type == "IMAGE_EDITOR"]
    if not editors:
        views = sorted((a for a in areas if a.type == "VIEW_3D"), key=lambda a: a.width * a.height)
        if not views:
            return False
        views[-1].type = "IMAGE_EDITOR"
        editors = [views[-1]]
    editors[0].spaces.active.image = dn_image
    editors[0].tag_redraw()
    try:  # redraw now, while the script still runs
        bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=1)
    except RuntimeError:
        pass
    return True


def main():
    args = parse_args()
    dn = import_dn(args.dn_module_dir)
    from dn_denoise.blender_image import to_blender_image  # the add-on's, beside this script
    from dn_denoise.camera import camera_matrices  # the camera as `dn denoise --camera` gets it

    scene = bpy.context.scene
    frames = frame_list(args.frames, scene)
    out_dir = args.out or os.path.join(os.path.dirname(bpy.data.filepath) or os.getcwd(), "denoised")
    parameters = {}
    for assignment in args.param:
        name, sep, value = assignment.partition("=")
        if not sep:
            raise SystemExit("denoise_render.py: --param %s: expected NAME=VALUE" % assignment)
        parameters[name] = float(value)

    conn = dn.connect(args.server, client_name="blender-denoise_render")
    pipeline = conn.find_pipeline(args.pipeline)
    if pipeline is None:
        raise SystemExit("denoise_render.py: %s has no pipeline '%s' (it offers: %s)" %
                         (conn.endpoint, args.pipeline, ", ".join(p.name for p in conn.pipelines())))
    configure(scene, args)
    render_dir = args.renders or tempfile.mkdtemp(prefix="dn-blender-")
    os.makedirs(render_dir, exist_ok=True)
    print("denoise_render.py: %s (%s), pipeline %s, frames %d..%d" %
          (conn.endpoint, conn.device_name, args.pipeline, frames[0], frames[-1]))

    session = None
    noisy = {}  # frame -> radiance, for the report
    totals = {"frames": 0, "latency": 0.0, "server": 0.0}

    def present(result):
        rgb = result.image
        image = to_blender_image(rgb)
        shown = show(image)
        if bpy.app.background or args.out:
            # dn.write_exr, not Image.save(): Blender 3.4 writes a float image's EXR through the
            # display transform (sRGB-encoded values), which a linear EXR must not have.
            os.makedirs(out_dir, exist_ok=True)
            dn.write_exr(os.path.join(out_dir, "denoised_%04d.exr" % result.frame_index), rgb)
        change = dn.relative_mse(rgb, noisy.pop(result.frame_index))
        totals["frames"] += 1
        totals["latency"] += result.latency_ms
        totals["server"] += result.total_timing_ms
        print("denoise_render.py: frame %d denoised: e2e %.1f ms, server %.1f ms, relMSE against the noisy "
              "render %.4f%s" % (result.frame_index, result.latency_ms, result.total_timing_ms, change,
                                 ", shown in the Image Editor" if shown else ""))

    try:
        for i, number in enumerate(frames):
            scene.frame_set(number)
            view, projection = camera_matrices(scene)
            t0 = time.monotonic()
            path = os.path.join(render_dir, "render_%04d.exr" % number)
            scene.render.filepath = path  # a still render does not expand '####'
            bpy.ops.render.render(write_still=True)
            frame = dn.read_frame(path, pipeline, preset="cycles", fp16=args.fp16, number=number,
                                  view=np.array(view), projection=np.array(projection))
            print("denoise_render.py: frame %d rendered in %.2f s (%dx%d) -> %s" %
                  (number, time.monotonic() - t0, frame.width, frame.height, path))
            if session is None:
                for name, source in frame.mapping.items():
                    print("denoise_render.py:   %-12s <- %s" % (name, source))
                session = conn.open_session(frame.width, frame.height, args.pipeline, channels=frame.channels,
                                            parameters=dict(frame.parameters, **parameters))
                print("denoise_render.py: session %d (watch it with: %s --output 'watch/%%04d.png')" %
                      (session.id, session.watch_command))
            noisy[number] = frame.planes["radiance"] if "radiance" in frame.planes else dn.read_exr_rgb(path)
            session.submit(frame, frame_index=number, reset=(i == 0))
            result = session.poll()
            while result is not None:
                present(result)
                result = session.poll()
        while session.in_flight:
            present(session.wait())
        session.close()
    finally:
        conn.close()
        if not args.renders:
            shutil.rmtree(render_dir, ignore_errors=True)
    n = max(totals["frames"], 1)
    print("denoise_render.py: %d frames, mean e2e %.1f ms, mean server %.1f ms%s" %
          (totals["frames"], totals["latency"] / n, totals["server"] / n,
           "; saved to " + out_dir if (bpy.app.background or args.out) else ""))


if __name__ == "__main__":
    try:
        main()
    except SystemExit:
        raise
    except Exception as e:  # Blender would print the traceback and still exit 0 in background mode
        import traceback
        traceback.print_exc()
        if bpy.app.background:
            sys.exit("denoise_render.py: %s: %s" % (type(e).__name__, e))
        raise
