"""dn.read_frame asks only for what the pipeline uses, and its errors speak Python (channels=...), not the CLI."""

import os

import numpy as np
import pytest

import dn
from conftest import SOURCE_DIR

CYCLES = os.path.join(SOURCE_DIR, "tests", "fixtures", "cycles")


def without(path, out, *passes):
    raw = dn.read_exr(path)
    dn.write_exr(out, {k: v for k, v in raw.items() if not any(p in k for p in passes)})
    return raw


def test_passthrough_reads_a_bare_rgba_exr_without_a_camera(conn, tmp_path):
    rgba = np.random.default_rng(3).uniform(0, 4, (36, 64, 4)).astype(np.float32)
    path = str(tmp_path / "bare.exr")
    dn.write_exr(path, rgba)
    frame = dn.read_frame(path, conn.find_pipeline("passthrough"))
    assert set(frame.planes) == {"radiance"}
    assert np.array_equal(frame.planes["radiance"], rgba[..., :3])
    assert frame.camera_source == "identity"


def test_passthrough_reads_cycles_without_denoising_data_or_position(conn, tmp_path):
    path = str(tmp_path / "stripped.exr")
    raw = without(os.path.join(CYCLES, "frame_0000.exr"), path, ".Denoising ", ".Position.")
    frame = dn.read_frame(path, conn.find_pipeline("passthrough"), preset="cycles")
    assert frame.camera_source == "identity"
    assert not any(name.startswith("reflection_") for name in frame.planes)
    # Depth as the file has it: Cycles' Depth pass, background made +inf.
    depth = raw["ViewLayer.Depth.Z"]
    assert np.array_equal(frame.planes["depth"], np.where(depth >= 1e9, np.inf, depth))


def test_a_missing_channel_is_mapped_with_channels(conn, tmp_path):
    path = str(tmp_path / "partial.exr")
    raw = without(os.path.join(CYCLES, "frame_0000.exr"), path, ".DiffCol.", ".Denoising Albedo.")
    svgf = conn.find_pipeline("svgf")
    with pytest.raises(dn.ChannelMapError) as e:
        dn.read_frame(path, svgf)
    message = str(e.value)
    assert "requires channel 'albedo'" in message
    assert "map it with channels={..., 'albedo': 'LAYER'}" in message
    assert "--channel" not in message
    # Mapped as the message says: exactly these channels, albedo from the layer given.
    frame = dn.read_frame(path, svgf, channels={"radiance": None, "albedo": "GlossCol", "normal": None,
                                                "depth": None, "motion": None})
    assert set(frame.planes) == {"radiance", "albedo", "normal", "depth", "motion"}
    gloss = np.stack([raw["ViewLayer.GlossCol.%s" % c] for c in "RGB"], axis=-1)
    assert np.array_equal(frame.planes["albedo"], gloss)
    assert "ViewLayer.GlossCol" in frame.mapping["albedo"]
    # A mapping the file cannot give, and an unknown name, in the same words.
    with pytest.raises(dn.ChannelMapError, match=r"^channels=\{\.\.\.\} maps channel 'albedo'") as e:
        dn.read_frame(path, svgf, channels={"radiance": None, "albedo": "NoSuchPass"})
    assert "--channel" not in str(e.value)
    with pytest.raises(dn.ChannelMapError, match=r"^channels=\[\.\.\.\]: unknown protocol channel 'albedoo'"):
        dn.read_frame(path, svgf, channels=["radiance", "albedoo"])
    with pytest.raises(TypeError, match="channels"):
        dn.read_frame(path, svgf, channels="radiance")


def test_a_missing_camera_is_given_with_camera_file(conn, tmp_path):
    path = str(tmp_path / "no_position.exr")
    without(os.path.join(CYCLES, "frame_0000.exr"), path, ".Position.")
    with pytest.raises(Exception) as e:
        dn.read_frame(path, conn.find_pipeline("svgf-fb"), preset="cycles")
    message = str(e.value)
    assert "has no camera" in message
    assert "give the cameras with camera_file=PATH" in message
    assert "--camera" not in message
