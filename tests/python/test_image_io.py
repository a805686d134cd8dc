"""EXR files, metrics and dn.read_frame (the `dn denoise` presets) from Python."""

import os
import subprocess

import numpy as np
import pytest

import dn
from conftest import SOURCE_DIR

CYCLES = os.path.join(SOURCE_DIR, "tests", "fixtures", "cycles")


def test_write_and_read_exr(tmp_path):
    rng = np.random.default_rng(10)
    rgb = rng.uniform(0, 50, (9, 13, 3)).astype(np.float32)
    path = str(tmp_path / "rgb.exr")
    dn.write_exr(path, rgb)
    channels = dn.read_exr(path)
    assert sorted(channels) == ["B", "G", "R"]
    assert np.array_equal(np.stack([channels[c] for c in "RGB"], axis=-1), rgb)
    assert np.array_equal(dn.read_exr_rgb(path), rgb)
    dn.write_exr(path, rgb, half=True)
    assert np.array_equal(dn.read_exr_rgb(path), rgb.astype(np.float16).astype(np.float32))
    dn.write_exr(path, {"depth.Z": rgb[..., 0], "mask.Y": rgb[..., 1]})
    channels = dn.read_exr(path)
    assert sorted(channels) == ["depth.Z", "mask.Y"] and np.array_equal(channels["depth.Z"], rgb[..., 0])
    with pytest.raises(dn.ImageError, match="nonexistent.exr"):
        dn.read_exr(str(tmp_path / "nonexistent.exr"))
    with pytest.raises(OSError):
        dn.read_exr_rgb(str(tmp_path / "nonexistent.exr"))
    with pytest.raises(ValueError, match="same height and width"):
        dn.write_exr(path, {"a": rgb[..., 0], "b": rgb[:4, :, 0]})


def test_metrics_match_their_definitions():
    rng = np.random.default_rng(11)
    a = rng.uniform(0, 2, (8, 8, 3)).astype(np.float32)
    ref = rng.uniform(0, 2, (8, 8, 3)).astype(np.float32)
    d = a.astype(np.float64) - ref
    assert dn.rmse(a, ref) == pytest.approx(np.sqrt(np.mean(d * d)), rel=1e-6)
    assert dn.relative_mse(a, ref) == pytest.approx(np.mean(d * d / (ref.astype(np.float64) ** 2 + 0.01)), rel=1e-6)
    with pytest.raises(ValueError, match="same shape"):
        dn.rmse(a, ref[:4])


def test_read_frame_maps_the_cycles_passes(conn):
    path = os.path.join(CYCLES, "frame_0000.exr")
    raw = dn.read_exr(path)
    frame = dn.read_frame(path, conn.find_pipeline("svgf"), preset="cycles")
    assert frame.preset == "cycles" and (frame.width, frame.height) == (64, 36)
    assert {"radiance", "albedo", "normal", "depth", "motion"} <= set(frame.planes)
    assert set(frame.channels) == set(frame.planes) and set(frame.channels.values()) == {"f32"}
    assert "ViewLayer.Combined" in frame.mapping["radiance"]
    # docs/client.md, "Preset cycles": radiance is Combined.RGB, motion (Vector.X, -Vector.Y).
    layer = lambda name, comps: np.stack([raw["ViewLayer.%s.%s" % (name, c)] for c in comps], axis=-1)
    assert np.array_equal(frame.planes["radiance"], layer("Combined", "RGB"))
    assert np.array_equal(frame.planes["normal"], layer("Normal", "XYZ"))
    vector = layer("Vector", "XY")
    assert np.array_equal(frame.planes["motion"], np.stack([vector[..., 0], -vector[..., 1]], axis=-1))
    assert frame.planes["depth"].shape == (36, 64)
    # No camera in a Cycles EXR: recovered from the Position pass.
    assert frame.camera_source == "Position pass" and frame.camera_residual_px < 0.1
    assert frame.view.shape == (4, 4) and frame.projection[3, 2] == -1  # [row, column]: OpenGL's w = -z
    fp16 = dn.read_frame(path, conn.find_pipeline("svgf"), fp16=True, channels=["radiance", "albedo", "normal",
                                                                               "depth", "motion"])
    assert set(fp16.channels.values()) == {"f16"}
    given = dn.read_frame(path, conn.find_pipeline("svgf"), view=np.eye(4), projection=frame.projection)
    assert given.camera_source == "given" and np.array_equal(given.view, np.eye(4))


def test_read_frame_names_the_missing_pass(conn, tmp_path):
    raw = dn.read_exr(os.path.join(CYCLES, "frame_0000.exr"))
    partial = {k: v for k, v in raw.items() if ".DiffCol." not in k and ".Denoising Albedo." not in k}
    path = str(tmp_path / "partial.exr")
    dn.write_exr(path, partial)
    with pytest.raises(dn.ChannelMapError, match="requires channel 'albedo'.*Diffuse: Color") as e:
        dn.read_frame(path, conn.find_pipeline("svgf"))
    assert isinstance(e.value, ValueError)
    with pytest.raises(dn.ChannelMapError, match="unknown preset 'blender'"):
        dn.read_frame(path, preset="blender")


def test_a_cycles_sequence_denoises_as_dn_denoise_does(conn, server, dn_tool, tmp_path):
    # The same frames through dn.read_frame + Session.submit and through the
    # dn tool must give the same pixels: same planes, cameras and session.
    svgf = conn.find_pipeline("svgf")
    frames = [dn.read_frame(os.path.join(CYCLES, "frame_%04d.exr" % i), svgf, number=i) for i in range(3)]
    with conn.open_session(64, 36, "svgf", channels=frames[0].channels) as s:
        for i, f in enumerate(frames):
            s.submit(f, frame_index=i, reset=(i == 0))
        ours = [s.wait().image for _ in frames]
    subprocess.run([dn_tool, "denoise", "--server", server.url, "--pipeline", "svgf", "--preset", "cycles", "-q",
                    "--input", os.path.join(CYCLES, "frame_%04d.exr"), "--start", "0", "--end", "2",
                    "--output", str(tmp_path / "den_%04d.exr"), "--exr-float"], check=True)
    for i, image in enumerate(ours):
        theirs = dn.read_exr_rgb(str(tmp_path / ("den_%04d.exr" % i)))
        assert np.array_equal(image, theirs), "frame %d" % i
    # And the filter helps: closer to the 64-spp reference than the 1-spp input.
    ref = dn.read_exr_rgb(os.path.join(CYCLES, "ref_0002.exr"))
    assert dn.relative_mse(ours[2], ref) < dn.relative_mse(frames[2].planes["radiance"], ref)
