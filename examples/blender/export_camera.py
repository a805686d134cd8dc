"""Writes the scene camera of every frame in dn denoise's --camera FILE format.

    blender -b scene.blend --python examples/blender/export_camera.py -- \
        --out cameras.txt [--start 1] [--end 8] [--camera NAME]

One line per frame (docs/client.md, "Cameras without headers"):

    frame <n> view <16 floats> projection <16 floats>

column-major, in the protocol's convention (docs/protocol.md §5.6.1):
`view` is world -> view, OpenGL style (right-handed, camera looking down -z,
y up) and `projection` is view -> clip, unjittered, clip y up. Blender's camera
space is exactly that (a camera looks down its local -Z with +Y up), so
`view` is the inverse of the camera's world matrix (scale removed, as Cycles
removes it) and `projection` is Blender's own
`Object.calc_matrix_camera(depsgraph, x, y, scale_x, scale_y)` for the render
resolution (resolution_x/y x percentage), the pixel aspect, the sensor fit and
the lens shift - the matrix the viewport uses for camera view, near/far from
the camera's clip start/end. World coordinates are Blender's (Z up), the same
space as the Position pass. --start/--end default to the scene's frame range;
--camera to the scene's active camera (markers binding cameras are followed:
scene.camera is read after each frame_set). Perspective cameras only:
orthographic and panoramic cameras are refused, since the pipelines assume
a pinhole.
"""

import argparse
import os
import sys

import bpy

# camera_matrices is the add-on's (dn_denoise/camera.py), beside this script.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from dn_denoise.camera import camera_matrices, column_major  # noqa: E402


def main(argv):
    parser = argparse.ArgumentParser(prog="export_camera.py")
    parser.add_argument("--out", required=True, help="camera file to write")
    parser.add_argument("--start", type=int, help="first frame (default: scene start)")
    parser.add_argument("--end", type=int, help="last frame, inclusive (default: scene end)")
    parser.add_argument("--camera", help="camera object name (default: the scene's active camera)")
    args = parser.parse_args(argv)

    scene = bpy.context.scene
    start = scene.frame_start if args.start is None else args.start
    end = scene.frame_end if args.end is None else args.end
    render = scene.render
    width = round(render.resolution_x * render.resolution_percentage / 100)
    height = round(render.resolution_y * render.resolution_percentage / 100)

    lines = ["# dn denoise --camera file: frame N view <16> projection <16> (column-major, OpenGL convention)",
             "# from %s, camera %s, %dx%d" % (bpy.data.filepath or "(unsaved)", args.camera or "scene.camera",
                                               width, height)]
    for frame in range(start, end + 1):
        scene.frame_set(frame)
        obj = bpy.data.objects[args.camera] if args.camera else scene.camera
        try:
            view, projection = camera_matrices(scene, obj)
        except ValueError as e:
            sys.exit("export_camera.py: %s" % e)
        numbers = lambda m: " ".join("%.9g" % v for v in column_major(m))
        lines.append("frame %d view %s projection %s" % (frame, numbers(view), numbers(projection)))
    with open(args.out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("export_camera.py: wrote %d frames to %s" % (end - start + 1, args.out))


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
