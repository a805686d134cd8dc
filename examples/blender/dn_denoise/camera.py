"""The scene camera as the protocol takes it (docs/protocol.md §5.6.1): see
examples/blender/export_camera.py, which writes it per frame for `dn denoise
--camera`."""

import bpy


def column_major(m):
    return [m[r][c] for c in range(4) for r in range(4)]


def camera_matrices(scene, obj=None):
    """(view, projection) of `obj` (default: scene.camera) at the current frame,
    as mathutils matrices indexed [row][column]; see the module docstring.
    Raises ValueError for a missing or non-perspective camera."""
    obj = obj or scene.camera
    if obj is None or obj.type != 'CAMERA':
        raise ValueError("frame %d: no camera (give --camera NAME)" % scene.frame_current)
    if obj.data.type != 'PERSP':
        raise ValueError("camera %s is %s; only Perspective cameras describe a pinhole "
                         "(Camera -> Lens -> Type)" % (obj.name, obj.data.type))
    render = scene.render
    width = round(render.resolution_x * render.resolution_percentage / 100)
    height = round(render.resolution_y * render.resolution_percentage / 100)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    loc, rot, _scale = evaluated.matrix_world.decompose()
    world = rot.to_matrix().to_4x4()
    world.translation = loc
    view = world.inverted()
    projection = evaluated.calc_matrix_camera(depsgraph, x=width, y=height,
                                              scale_x=render.pixel_aspect_x, scale_y=render.pixel_aspect_y)
    return view, projection
