"""Denoised pixels as a Blender image (the add-on's result, and denoise_render.py's)."""

import bpy
import numpy as np

IMAGE_NAME = "dn denoised"


def to_blender_image(rgb, name=IMAGE_NAME):
    """(H, W, 3) float32, rows top-first -> a float Blender image (RGBA, rows bottom-first)."""
    h, w, _ = rgb.shape
    image = bpy.data.images.get(name)
    if image is None or tuple(image.size) != (w, h):
        if image is not None:
            bpy.data.images.remove(image)
        image = bpy.data.images.new(name, width=w, height=h, alpha=False, float_buffer=True)
    rgba = np.ones((h, w, 4), np.float32)
    rgba[..., :3] = rgb[::-1]
    image.pixels.foreach_set(rgba.ravel())
    image.update()
    return image
