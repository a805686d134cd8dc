"""examples/blender/denoise_render.py and the add-on dn_denoise inside Blender
against a real dnserver (ctest python_blender_example; run only when `blender`
is on PATH).

The project's Cycles room (examples/blender/cycles_room.py) is built at
128x72, three frames of its moving camera are rendered at 1 spp and denoised
through svgf by the example; the same frames rendered at 64 spp (another
seed) are the reference. The denoised frames must be finite, the Blender
image must hold what was saved, and each frame must be closer to the
reference than the noisy render."""

import os
import shutil
import subprocess

import numpy as np
import pytest

import dn
from conftest import SOURCE_DIR

pytestmark = pytest.mark.blender

BLENDER = shutil.which("blender")
EXAMPLES = os.path.join(SOURCE_DIR, "examples", "blender")
W, H, FRAMES = 128, 72, 3


def blender(*args, timeout=300):
    if not BLENDER:
        pytest.skip("blender is not on PATH")
    p = subprocess.run([BLENDER, "-b", "--factory-startup", *args], capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stdout + p.stderr


def build_room(out, spp, seed):
    """A --python-expr that builds cycles_room.py's scene with these settings (no render)."""
    return ("import sys, argparse; sys.path.insert(0, %r); import cycles_room as r; "
            "a = argparse.Namespace(out=%r, name='frame', width=%d, height=%d, frames=%d, spp=%d, seed=%d, start=0, "
            "half=False, threads=0, passes='default'); r.configure(r.build_scene(a), a)" % (EXAMPLES, out, W, H, FRAMES, spp, seed))


# After the example: the Blender image it left must hold the last frame's pixels
# (Blender's rows are bottom-first), the same as the EXR it saved.
CHECK_IMAGE = """
import sys, numpy as np, bpy
sys.path.insert(0, %r)
import dn
image = bpy.data.images["dn denoised"]
w, h = image.size
pixels = np.empty(w * h * 4, np.float32)
image.pixels.foreach_get(pixels)
saved = dn.read_exr_rgb(%r)
same = np.array_equal(pixels.reshape(h, w, 4)[::-1, :, :3], saved)
print("check: the Blender image %%s the saved frame" %% ("holds" if same else "DIFFERS FROM"))
sys.exit(0 if same else 3)
"""


def test_denoise_render_in_blender(server, tmp_path):
    renders, out = tmp_path / "renders", tmp_path / "denoised"
    module_dir = os.environ.get("PYTHONPATH", "").split(os.pathsep)[0]
    rc, log = blender("--python-expr", build_room(str(renders), 1, 0),
                      "--python", os.path.join(EXAMPLES, "denoise_render.py"),
                      "--python-expr", CHECK_IMAGE % (module_dir, str(out / ("denoised_%04d.exr" % (FRAMES - 1)))),
                      "--", "--server", server.url, "--frames", "0..%d" % (FRAMES - 1), "--out", str(out),
                      "--renders", str(renders), "--dn-module-dir", module_dir)
    print(log)
    assert rc == 0, log
    assert "check: the Blender image holds the saved frame" in log
    assert "radiance     <- ViewLayer.Combined.{R,G,B}" in log
    assert "%d frames, mean e2e" % FRAMES in log

    # The reference: the same frames at 64 spp with another seed, by cycles_room.py itself.
    ref_dir = tmp_path / "ref"
    rc, ref_log = blender("--python", os.path.join(EXAMPLES, "cycles_room.py"), "--", "--out", str(ref_dir),
                          "--name", "ref", "--width", str(W), "--height", str(H), "--frames", str(FRAMES),
                          "--spp", "64", "--seed", "1")
    assert rc == 0, ref_log

    for i in range(FRAMES):
        denoised = dn.read_exr_rgb(str(out / ("denoised_%04d.exr" % i)))
        noisy = dn.read_exr_rgb(str(renders / ("render_%04d.exr" % i)))
        ref = dn.read_exr_rgb(str(ref_dir / ("ref_%04d.exr" % i)))
        assert denoised.shape == (H, W, 3) and np.all(np.isfinite(denoised))
        noisy_error, denoised_error = dn.relative_mse(noisy, ref), dn.relative_mse(denoised, ref)
        print("frame %d: relMSE against the 64-spp reference: noisy %.4f, denoised %.4f; "
              "denoised against noisy %.4f" % (i, noisy_error, denoised_error, dn.relative_mse(denoised, noisy)))
        assert denoised_error < 0.5 * noisy_error, "frame %d" % i


def test_denoise_render_reports_a_missing_pipeline(server, tmp_path):
    rc, log = blender("--python", os.path.join(EXAMPLES, "denoise_render.py"), "--", "--server", server.url,
                      "--pipeline", "no-such-pipeline", "--width", "32", "--height", "18", "--samples", "1",
                      "--out", str(tmp_path), "--dn-module-dir", os.environ.get("PYTHONPATH", "").split(os.pathsep)[0])
    assert rc != 0 and "has no pipeline 'no-such-pipeline' (it offers: " in log, log


# The add-on as a user has it: installed from its zip, enabled, the passes it
# reads turned on, a render, then its operator; the image it made and the
# noisy render are saved for the comparison here.
ADDON_RUN = """
import argparse, sys, bpy, numpy as np
sys.path.insert(0, %(examples)r)
import cycles_room as r
a = argparse.Namespace(out=%(out)r, name="frame", width=%(w)d, height=%(h)d, frames=1, spp=1, seed=0, start=0,
                       half=False, threads=0, passes="default")
scene = r.build_scene(a)  # first: it reads the factory settings, which would disable the add-on
r.configure(scene, a)
bpy.ops.preferences.addon_install(filepath=%(zip)r)
bpy.ops.preferences.addon_enable(module="dn_denoise")
prefs = bpy.context.preferences.addons["dn_denoise"].preferences
prefs.server, prefs.module_dir = %(server)r, %(module_dir)r
bpy.ops.dn.use_passes()
bpy.ops.render.render()
bpy.data.images["Render Result"].save_render(%(noisy)r, scene=scene)
print("addon: operator", bpy.ops.dn.denoise_render())
image = bpy.data.images["dn denoised"]
print("addon: pipeline %%s: %%s" %% (image["dn_pipeline"], image["dn_reason"]))
w, h = image.size
pixels = np.empty(w * h * 4, np.float32)
image.pixels.foreach_get(pixels)
np.save(%(denoised)r, pixels.reshape(h, w, 4)[::-1, :, :3])
"""


def test_addon_from_its_zip_denoises_a_render(server, tmp_path):
    addon_zip = os.environ.get("DN_BLENDER_ADDON_ZIP", "")
    assert os.path.isfile(addon_zip), "DN_BLENDER_ADDON_ZIP=%r: build the target dn_blender_addon" % addon_zip
    module_dir = os.environ.get("PYTHONPATH", "").split(os.pathsep)[0]
    noisy_path, denoised_path = tmp_path / "noisy.exr", tmp_path / "denoised.npy"
    script = ADDON_RUN % {"zip": addon_zip, "server": server.url, "module_dir": module_dir, "examples": EXAMPLES,
                          "out": str(tmp_path), "w": W, "h": H, "noisy": str(noisy_path),
                          "denoised": str(denoised_path)}
    # Its own user scripts folder: the install must not touch the user's Blender.
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(tmp_path / "scripts"))
    if not BLENDER:
        pytest.skip("blender is not on PATH")
    p = subprocess.run([BLENDER, "-b", "--factory-startup", "--python-expr", script], capture_output=True, text=True,
                       timeout=300, env=env)
    log = p.stdout + p.stderr
    print(log)
    assert p.returncode == 0, log
    assert "addon: operator {'FINISHED'}" in log
    # Combined, Z, Normal, Diffuse Color and Denoising Data, no Vector: one frame with its guides.
    assert "addon: pipeline image: one frame at a time" in log

    rc, ref_log = blender("--python", os.path.join(EXAMPLES, "cycles_room.py"), "--", "--out", str(tmp_path / "ref"),
                          "--name", "ref", "--width", str(W), "--height", str(H), "--frames", "1", "--spp", "64",
                          "--seed", "1", "--passes", "default")
    assert rc == 0, ref_log
    ref = dn.read_exr_rgb(str(tmp_path / "ref" / "ref_0000.exr"))
    noisy = dn.read_exr_rgb(str(noisy_path))
    denoised = np.load(str(denoised_path))
    assert denoised.shape == (H, W, 3) and np.all(np.isfinite(denoised))
    noisy_error, denoised_error = dn.relative_mse(noisy, ref), dn.relative_mse(denoised, ref)
    print("add-on: relMSE against the 64-spp reference: noisy %.4f, denoised %.4f" % (noisy_error, denoised_error))
    assert denoised_error < noisy_error
