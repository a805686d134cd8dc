"""Builds the project's second Blender Cycles scene, a room lit through a window, and renders it.

    blender -b --factory-startup --python examples/blender/cycles_window.py -- \
        --out DIR [--width 320] [--height 180] [--frames 8] [--spp 1] [--seed 0] [--start 0]
        [--name frame] [--half] [--threads N] [--passes preset|denoising|all] [--still]

The options, the render settings, the passes (--passes) and the file layout
are cycles_room.py's (this script imports it): DIR/NAME_%04d.exr, one
multilayer OpenEXR per frame, view layer "ViewLayer".

The scene: a closed 5 x 6 x 2.8 m room whose only opening is a window
(2 x 1.4 m) in the left wall; outside, a sun shining in through it at 30
degrees (a bright patch on the floor) and a blue sky. Everything else is lit
indirectly, by light bounced off that patch and the walls. Walls, floor and
ceiling carry procedural textures (bricks on the back wall, noise on the side
walls and the ceiling, wood-like waves on a glossy floor: the diffuse colour
varies within a surface). In the room: a glass sphere (transmission 1,
IOR 1.45, roughness 0) standing in the sun patch, a copper cylinder
(metal, roughness 0.15) and a glossy red box (dielectric, roughness 0.1).
The camera pans and dollies as in cycles_room.py (linear keys at --start and
--start + 11, extrapolated). Every material writes the Roughness and
SpecularF0 AOVs, which only --passes all declares.
"""

import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cycles_room as room  # noqa: E402  (the shared options, settings and materials)

W, D, H = 5.0, 6.0, 2.8  # room: x in [-W/2, W/2], y in [-D/2, D/2], z in [0, H]
WINDOW_Y = (-0.4, 1.6)  # the opening in the wall x = -W/2
WINDOW_Z = (0.8, 2.2)


def colour_ramp(nt, fac_socket, c1, c2):
    """fac in [0, 1] -> a colour between c1 and c2."""
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (*c1, 1.0)
    ramp.color_ramp.elements[1].color = (*c2, 1.0)
    nt.links.new(fac_socket, ramp.inputs["Fac"])
    return ramp.outputs["Color"]


def texture_colour(nt, kind, c1, c2, scale):
    """A procedural colour in object space (metres): bricks, noise or waves."""
    coord = nt.nodes.new("ShaderNodeTexCoord")
    if kind == "brick":
        tex = nt.nodes.new("ShaderNodeTexBrick")
        tex.inputs["Color1"].default_value = (*c1, 1.0)
        tex.inputs["Color2"].default_value = (*c2, 1.0)
        tex.inputs["Mortar"].default_value = (0.75, 0.74, 0.7, 1.0)
        tex.inputs["Scale"].default_value = scale
        nt.links.new(coord.outputs["Object"], tex.inputs["Vector"])
        return tex.outputs["Color"]
    tex = nt.nodes.new("ShaderNodeTexNoise" if kind == "noise" else "ShaderNodeTexWave")
    tex.inputs["Scale"].default_value = scale
    if kind == "wave":
        tex.inputs["Distortion"].default_value = 6.0
    nt.links.new(coord.outputs["Object"], tex.inputs["Vector"])
    return colour_ramp(nt, tex.outputs["Fac"], c1, c2)


def textured_diffuse(name, kind, c1, c2, scale):
    m, nt = room.new_material(name)
    bsdf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(texture_colour(nt, kind, c1, c2, scale), bsdf.inputs["Color"])
    nt.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
    room.add_aovs(nt, 1.0, (0.0, 0.0, 0.0))
    return m


def textured_glossy_floor():
    m = room.principled("floor_wood", (0.4, 0.25, 0.12), 0.0, 0.3, specular=0.5)
    nt = m.node_tree
    bsdf = next(n for n in nt.nodes if n.bl_idname == "ShaderNodeBsdfPrincipled")
    colour = texture_colour(nt, "wave", (0.30, 0.17, 0.08), (0.55, 0.36, 0.18), 1.5)
    nt.links.new(colour, bsdf.inputs["Base Color"])
    return m


def wall_with_window(material):
    """The wall x = -W/2, facing +x, as four planes around the opening."""
    (y0, y1), (z0, z1) = WINDOW_Y, WINDOW_Z
    rot = (math.pi / 2, 0, math.pi / 2)  # plane's local x -> world y, local y -> world z
    x = -W / 2
    room.plane("wall_window_below", (D, z0), (x, 0, z0 / 2), rot, material)
    room.plane("wall_window_above", (D, H - z1), (x, 0, (z1 + H) / 2), rot, material)
    room.plane("wall_window_near", (y0 + D / 2, z1 - z0), (x, (y0 - D / 2) / 2, (z0 + z1) / 2), rot, material)
    room.plane("wall_window_far", (D / 2 - y1, z1 - z0), (x, (y1 + D / 2) / 2, (z0 + z1) / 2), rot, material)


def build_scene(a):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene

    plaster = textured_diffuse("wall_plaster", "noise", (0.62, 0.6, 0.55), (0.82, 0.8, 0.75), 3.0)
    bricks = textured_diffuse("wall_bricks", "brick", (0.45, 0.16, 0.1), (0.6, 0.3, 0.18), 2.0)
    ceiling = textured_diffuse("ceiling", "noise", (0.7, 0.7, 0.68), (0.8, 0.8, 0.78), 6.0)
    room.plane("floor", (W, D), (0, 0, 0), (0, 0, 0), textured_glossy_floor())
    room.plane("ceiling", (W, D), (0, 0, H), (math.pi, 0, 0), ceiling)
    room.plane("wall_back", (W, H), (0, D / 2, H / 2), (math.pi / 2, 0, 0), bricks)
    room.plane("wall_front", (W, H), (0, -D / 2, H / 2), (-math.pi / 2, 0, 0), plaster)
    room.plane("wall_right", (D, H), (W / 2, 0, H / 2), (math.pi / 2, 0, -math.pi / 2), plaster)
    wall_with_window(plaster)

    glass = room.principled("glass", (1.0, 1.0, 1.0), 0.0, 0.0, transmission=1.0, ior=1.45,
                            f0=(((1.45 - 1.0) / (1.45 + 1.0)) ** 2,) * 3)
    copper = room.principled("copper", (0.95, 0.64, 0.54), 1.0, 0.15)
    red = room.principled("glossy_red", (0.6, 0.05, 0.04), 0.0, 0.1, specular=0.5)
    room.sphere("glass_sphere", 0.45, (-0.5, 0.7, 0.45), glass)
    bpy.ops.mesh.primitive_cylinder_add(vertices=96, radius=0.3, depth=0.9, location=(0.7, 1.5, 0.45))
    cyl = bpy.context.active_object
    cyl.name = "copper_cylinder"
    bpy.ops.object.shade_smooth()
    cyl.data.materials.append(copper)
    bpy.ops.mesh.primitive_cube_add(size=0.6, location=(1.1, 0.2, 0.3), rotation=(0, 0, math.radians(30)))
    box = bpy.context.active_object
    box.name = "red_box"
    box.data.materials.append(red)

    # The sun, outside, shining in through the window: down at 30 degrees,
    # into the room (+x) and a little toward the back wall.
    sun_data = bpy.data.lights.new("sun", type="SUN")
    sun_data.energy = 8.0
    sun_data.angle = math.radians(1.0)
    sun = bpy.data.objects.new("sun", sun_data)
    sun.rotation_euler = (0.0, math.radians(-60), math.radians(20))
    sun.location = (-5.0, 0.6, 4.0)
    scene.collection.objects.link(sun)

    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.45, 0.6, 0.9, 1.0)
    bg.inputs["Strength"].default_value = 2.0
    scene.world = world

    # Camera: in the right front corner, looking past the glass sphere toward
    # the back-left corner (the window on the left of the frame); pans and dollies.
    cam_data = bpy.data.cameras.new("camera")
    cam_data.lens = 24.0
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.location = (1.9, -2.6, 1.5)
    cam.rotation_euler = (math.radians(78), 0, math.radians(38))
    cam.keyframe_insert("location", frame=a.start)
    cam.keyframe_insert("rotation_euler", frame=a.start)
    cam.location = (1.3, -2.0, 1.4)
    cam.rotation_euler = (math.radians(80), 0, math.radians(30))
    cam.keyframe_insert("location", frame=a.start + 11)
    cam.keyframe_insert("rotation_euler", frame=a.start + 11)
    for fc in cam.animation_data.action.fcurves:
        fc.extrapolation = "LINEAR"
        for k in fc.keyframe_points:
            k.interpolation = "LINEAR"
    scene.frame_start, scene.frame_end = a.start, a.start + a.frames - 1
    return scene


if __name__ == "__main__":
    room.run("cycles_window", __doc__, build_scene)
