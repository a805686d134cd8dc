"""examples/blender/denoise_render.py inside Blender against a real dnserver
(ctest python_blender_example; run only when `blender` is on PATH).

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
            "half=False, threads=0); r.configure(r.build_scene(a), a)" % (EXAMPLES, out, W, H, FRAMES, spp, seed))


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
