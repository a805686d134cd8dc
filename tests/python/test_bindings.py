"""The dn module against a real dnserver: what each call returns, checked
against expectations computed here (NumPy), and the errors it raises."""

import threading
import time

import numpy as np
import pytest

import dn

W, H = 64, 36
SVGF = {"radiance": "f32", "albedo": "f32", "normal": "f32", "depth": "f32", "motion": "f32"}


def still_scene(rng, w=W, h=H, dtype=np.float32):
    """A grey wall facing the camera one metre away, with noisy radiance."""
    normal = np.zeros((h, w, 3), dtype)
    normal[..., 2] = 1
    return {
        "radiance": rng.uniform(0.0, 1.0, (h, w, 3)).astype(dtype),
        "albedo": np.full((h, w, 3), 0.8, dtype),
        "normal": normal,
        "depth": np.ones((h, w), dtype),
        "motion": np.zeros((h, w, 2), dtype),
    }


# ---- connection -----------------------------------------------------------------------------------


def test_connection_reports_the_servers_welcome(conn, server):
    assert conn.endpoint == server.url
    assert conn.protocol_version == dn.PROTOCOL_VERSION == (1, 10)
    assert conn.is_open
    assert conn.limits["max_width"] >= W and conn.limits["max_frames_in_flight"] >= 1
    names = [p.name for p in conn.pipelines()]
    for name in ("passthrough", "accumulate", "svgf"):
        assert name in names
    svgf = conn.find_pipeline("svgf")
    assert {"albedo", "normal", "depth", "motion"} <= set(svgf.required)
    assert "radiance" in svgf.optional
    params = {p.name: p for p in svgf.parameters}
    assert params["alpha_colour"].min == 0 and params["alpha_colour"].max == 1
    assert params["max_history"].integer
    assert conn.find_pipeline("no-such-pipeline") is None
    assert conn.ping() > 0
    assert "frames_processed" in conn.stats()


def test_connect_without_url_uses_dn_server_then_the_default(server, monkeypatch):
    monkeypatch.setenv("DN_SERVER", server.url)
    with dn.connect() as c:
        assert c.endpoint == server.url
    monkeypatch.delenv("DN_SERVER")
    assert dn.DEFAULT_SERVER_URL == "tcp://127.0.0.1:7878"
    try:
        dn.connect(connect_timeout=2).close()  # something listens there: nothing to check
    except dn.TransportError as e:
        assert "tcp://127.0.0.1:7878" in str(e) and e.endpoint == "tcp://127.0.0.1:7878"


def test_connection_errors():
    with pytest.raises(dn.UsageError, match="IPv6 addresses must be in brackets") as e:
        dn.connect("tcp://::1:80")
    assert isinstance(e.value, ValueError) and e.value.kind == "usage"
    with pytest.raises(dn.TransportError) as e:
        dn.connect("unix:///nonexistent/dn.sock", connect_timeout=2)
    assert e.value.kind == "transport" and "unix:///nonexistent/dn.sock" in str(e.value)


def test_closed_connection_and_session_raise(server):
    c = dn.connect(server.url)
    with c:
        with c.open_session(W, H, "passthrough", channels=["radiance"]) as s:
            assert s.is_open
        assert not s.is_open and s.close() is None
        with pytest.raises(dn.UsageError, match="closed"):
            s.denoise({"radiance": np.zeros((H, W, 3), np.float32)})
        s2 = c.open_session(W, H, "passthrough", channels=["radiance"])
    assert not c.is_open
    with pytest.raises(dn.TransportError):
        s2.denoise({"radiance": np.zeros((H, W, 3), np.float32)})


# ---- exact pipelines ------------------------------------------------------------------------------


def test_passthrough_returns_the_radiance_exactly(conn):
    rng = np.random.default_rng(1)
    radiance = rng.uniform(-2.0, 1e4, (H, W, 3)).astype(np.float32)  # finite values are not sanitized
    radiance[0, 0] = [np.inf, -np.inf, np.nan]
    with conn.open_session(W, H, "passthrough", channels={"radiance": "f32"}) as s:
        assert s.channels == {"radiance": "f32"} and s.pipeline == "passthrough"
        out = s.denoise({"radiance": radiance})
    assert out.dtype == np.float32 and out.shape == (H, W, 3)
    assert np.array_equal(out, np.where(np.isfinite(radiance), radiance, 0.0))  # non-finite: 0


def test_auto_is_the_default_and_names_its_choice(conn):
    auto = conn.find_pipeline("auto")
    assert auto is not None and auto.required == [] and auto.parameters == []
    rng = np.random.default_rng(3)
    radiance = rng.uniform(0.4, 0.6, (H, W, 3)).astype(np.float32)
    with conn.open_session(W, H, channels=["radiance"]) as s:  # no pipeline named: auto
        assert s.pipeline == "image"
        assert s.pipeline_reason.startswith("one frame at a time")
        out = s.denoise({"radiance": radiance})
    # A constant 0.5 under uniform noise: the output is nearer to it than the input.
    assert np.mean((out - 0.5) ** 2) < np.mean((radiance - 0.5) ** 2)
    with conn.open_session(W, H, "auto") as s:  # the default channels: svgf's five
        assert s.pipeline == "svgf"
    with conn.open_session(W, H, "passthrough", channels=["radiance"]) as s:
        assert s.pipeline_reason == ""


def test_non_contiguous_and_float64_arrays_are_converted(conn):
    rng = np.random.default_rng(2)
    big = rng.uniform(0, 1, (H, 2 * W, 3))  # float64
    view = big[:, ::2]  # not contiguous
    with conn.open_session(W, H, "passthrough", channels=["radiance"]) as s:
        out = s.denoise({"radiance": view})
    assert np.array_equal(out, view.astype(np.float32))


def test_fp16_planes_and_output(conn):
    rng = np.random.default_rng(3)
    radiance = rng.uniform(0, 100, (H, W, 3)).astype(np.float32)
    half = radiance.astype(np.float16)
    with conn.open_session(W, H, "passthrough", channels={"radiance": "f16"}) as s:
        assert s.channels == {"radiance": "f16"}
        assert np.array_equal(s.denoise({"radiance": half}), half.astype(np.float32))  # sent as is
        assert np.array_equal(s.denoise({"radiance": radiance}), half.astype(np.float32))  # converted by the client
    with conn.open_session(W, H, "passthrough", channels={"radiance": np.float32}, output_format="f16") as s:
        r = (s.submit({"radiance": radiance}), s.wait())[1]
        assert r.format == "f16" and r.image.dtype == np.float32
        assert np.array_equal(r.image, half.astype(np.float32))


def test_accumulate_over_still_frames_is_the_mean(conn):
    # docs/pipelines.md, "accumulate in detail": with zero motion every tap is the
    # pixel itself (weight 1), len = frames so far, alpha = max(1/len, alpha_min):
    # alpha_min = 0 makes the output the running mean of the inputs.
    rng = np.random.default_rng(4)
    normal = np.zeros((H, W, 3), np.float32)
    normal[..., 2] = 1
    still = {"normal": normal, "depth": np.full((H, W), 2.0, np.float32), "motion": np.zeros((H, W, 2), np.float32)}
    inputs = []
    with conn.open_session(W, H, "accumulate", channels=["radiance", "normal", "depth", "motion"],
                           parameters={"alpha_min": 0.0, "max_history": 64}) as s:
        for i in range(8):
            inputs.append(rng.uniform(0, 4, (H, W, 3)).astype(np.float32))
            out = s.denoise(dict(still, radiance=inputs[-1]), reset=(i == 0))
            expected = np.mean(np.stack(inputs).astype(np.float64), axis=0)
            # fp32 running mean: a few roundings (measured at most 2.6e-7 relative after 8 frames).
            np.testing.assert_allclose(out, expected, rtol=2e-6, atol=1e-6)
        # A reset drops the history: the output is the frame itself.
        fresh = rng.uniform(0, 4, (H, W, 3)).astype(np.float32)
        assert np.array_equal(s.denoise(dict(still, radiance=fresh), reset=True), fresh)
        # RESULT.samples (protocol 1.9): every pixel of the still view rests on the frames since the reset.
        for k in (2, 3):
            s.submit(dict(still, radiance=fresh))
            assert s.wait().samples == (k, k)
    # Past max_history the mean becomes an exponential average: out = mix(prev, c, 1 / max_history).
    with conn.open_session(W, H, "accumulate", channels=["radiance", "normal", "depth", "motion"],
                           parameters={"alpha_min": 0.0, "max_history": 3}) as s:
        expected = None
        for i in range(7):
            c = rng.uniform(0, 4, (H, W, 3)).astype(np.float32)
            out = s.denoise(dict(still, radiance=c))
            expected = c.astype(np.float64) if i == 0 else expected + (c - expected) / min(i + 1, 3)
            np.testing.assert_allclose(out, expected, rtol=2e-6, atol=1e-6)


# ---- pipelined frames -----------------------------------------------------------------------------


def test_pipelined_submit_wait_in_order(conn):
    frames = [np.full((H, W, 3), float(i), np.float32) for i in range(10)]
    with conn.open_session(W, H, "passthrough", channels=["radiance"], max_in_flight=3) as s:
        assert s.max_in_flight == 3
        indices, results = [], []
        for f in frames:
            indices.append(s.submit({"radiance": f}))
            assert s.in_flight <= 3 + len(indices) - len(results)
            r = s.poll()
            while r is not None:
                results.append(r)
                r = s.poll()
        while s.in_flight:
            results.append(s.wait())
        assert indices == list(range(10))
        assert all(r.samples is None for r in results)  # passthrough keeps no count
        assert [r.frame_index for r in results] == indices
        for r, f in zip(results, frames):
            assert r.session_id == s.id and (r.width, r.height) == (W, H)
            assert np.array_equal(r.image, f)
            assert r.latency_ms > 0 and r.total_timing_ms >= 0 and "upload" in r.timings
        # Explicit indices must increase.
        assert s.submit({"radiance": frames[0]}, frame_index=100) == 100
        assert s.wait().frame_index == 100
        with pytest.raises(dn.UsageError, match="not greater") as e:
            s.submit({"radiance": frames[0]}, frame_index=100)
        assert e.value.code == "OutOfOrder"
        # no_output: the history advances, no image comes back.
        s.submit({"radiance": frames[1]}, no_output=True)
        assert s.wait().image is None


def test_wait_without_frames_raises(conn):
    with conn.open_session(W, H, "passthrough", channels=["radiance"]) as s:
        assert s.poll() is None
        with pytest.raises(dn.UsageError, match="no frame in flight"):
            s.wait()


# ---- watching -------------------------------------------------------------------------------------


def test_watcher_sees_the_shared_noisy_input(conn, server):
    frame = still_scene(np.random.default_rng(9))
    with dn.connect(server.url, client_name="watcher") as other:
        with conn.open_session(W, H, "svgf", channels=SVGF, share_input=True) as s:
            w = other.attach(s.id, s.watch_key)
            image = s.denoise(frame, reset=True)
            seen = w.next(timeout=30)
            assert np.array_equal(seen.image, image)
            assert np.array_equal(seen.input, frame["radiance"])  # exactly what the owner sent


def test_watcher_sees_the_owners_pixels(conn, server):
    rng = np.random.default_rng(5)
    frames = [still_scene(rng) for _ in range(3)]
    owned = []
    with dn.connect(server.url, client_name="watcher") as other:
        s = conn.open_session(W, H, "svgf", channels=SVGF)
        assert len(s.watch_key) == 32 and str(s.id) in s.watch_command and s.watch_key in s.watch_command
        w = other.attach(s.id, s.watch_key)
        assert w.session_id == s.id and (w.width, w.height) == (W, H) and w.pipeline == "svgf"
        owned.append(s.denoise(frames[0], reset=True))
        first = w.next(timeout=30)
        assert first.frame_index == 0 and first.latency_ms == 0
        assert np.array_equal(first.image, owned[0])
        for f in frames[1:]:
            owned.append(s.denoise(f))
        assert s.close() == 3
        seen = list(w)  # the newest of what arrived, until the session ended
        assert seen and seen[-1].frame_index == 2
        assert np.array_equal(seen[-1].image, owned[2])
        assert w.closed == 3 and w.next(timeout=1) is None
        assert first.input is None  # the owner did not share its input
        # The key is the capability: a wrong one is refused by the server, a malformed one locally.
        s2 = conn.open_session(W, H, "passthrough", channels=["radiance"])
        with pytest.raises(dn.ServerError) as e:
            other.watch(s2.id, "0" * 32)
        assert e.value.code == "UnknownSession"
        with pytest.raises(dn.UsageError) as e:
            other.attach(s2.id, "not-a-key")
        assert e.value.field == "ATTACH.watch_key"
        s2.close()


def test_blocking_calls_release_the_gil(conn, server):
    # A watcher thread blocks in next() while this thread sends the frame it
    # waits for; with the GIL held by the waiting thread this would time out.
    with dn.connect(server.url) as other:
        s = conn.open_session(W, H, "passthrough", channels=["radiance"])
        w = other.attach(s.id, s.watch_key)
        got = {}
        t = threading.Thread(target=lambda: got.update(r=w.next(timeout=30)))
        t0 = time.monotonic()
        t.start()
        time.sleep(0.2)
        s.denoise({"radiance": np.full((H, W, 3), 7.0, np.float32)})
        t.join(40)
        assert got["r"] is not None and np.all(got["r"].image == 7.0)
        assert time.monotonic() - t0 < 20
        s.close()


def test_sessions_of_one_connection_from_three_threads(conn):
    # The module serialises the calls of one connection's objects (docs/client.md, "Threads"):
    # three threads streaming on three sessions of it each get their own frames back.
    sessions = [conn.open_session(W, H, "passthrough", channels=["radiance"]) for _ in range(3)]
    failures = []

    def stream(k):
        try:
            for i in range(40):
                frame = np.full((H, W, 3), 100.0 * k + i, np.float32)
                if not np.array_equal(sessions[k].denoise({"radiance": frame}), frame):
                    failures.append((k, i))
        except Exception as e:  # noqa: BLE001 - reported below
            failures.append((k, repr(e)))

    threads = [threading.Thread(target=stream, args=(k,)) for k in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not failures
    for s in sessions:
        assert s.close() == 40


# ---- errors naming the culprit ------------------------------------------------------------------


def test_wrong_shape_names_the_channel_and_the_expected_shape(conn):
    rng = np.random.default_rng(6)
    with conn.open_session(W, H, "svgf", channels=SVGF) as s:
        bad = still_scene(rng)
        bad["albedo"] = bad["albedo"][..., 0]
        with pytest.raises(ValueError, match=r"channel 'albedo' has shape \(36, 64\).*expects \(36, 64, 3\)") as e:
            s.denoise(bad)
        assert isinstance(e.value, dn.UsageError) and e.value.code == "InvalidChannel"
        bad = still_scene(rng, w=W + 1)
        with pytest.raises(dn.UsageError, match=r"channel '\w+' has shape \(36, 65"):
            s.denoise(bad)
        ok = still_scene(rng)
        ok["depth"] = ok["depth"][..., None]  # (H, W, 1) is a one-component plane too
        assert s.denoise(ok, reset=True).shape == (H, W, 3)


def test_missing_unknown_and_undeclared_channels(conn):
    rng = np.random.default_rng(7)
    with conn.open_session(W, H, "svgf", channels=SVGF) as s:
        frame = still_scene(rng)
        del frame["depth"]
        with pytest.raises(dn.UsageError, match="channel 'depth' was declared .* missing") as e:
            s.denoise(frame)
        assert e.value.code == "MissingChannel"
        frame = still_scene(rng)
        frame["albdo"] = frame.pop("albedo")
        with pytest.raises(dn.UsageError, match="unknown channel 'albdo'; channels are: radiance, diffuse"):
            s.denoise(frame)
        frame = still_scene(rng)
        frame["emission"] = np.zeros((H, W, 3), np.float32)
        with pytest.raises(dn.UsageError, match="channel 'emission' was not declared"):
            s.denoise(frame)
        frame = still_scene(rng)
        frame["radiance"] = frame["radiance"].astype(np.int32)
        with pytest.raises(TypeError, match="channel 'radiance': dtype int32"):
            s.denoise(frame)
        with pytest.raises(TypeError, match="dict of channel name"):
            s.denoise([frame["radiance"]])
        # The session is still usable after every local refusal.
        assert np.all(np.isfinite(s.denoise(still_scene(rng), reset=True)))


def test_open_session_errors_name_the_culprit(conn):
    with pytest.raises(dn.ServerError, match="no-such-pipeline") as e:
        conn.open_session(W, H, "no-such-pipeline", channels=["radiance"])
    assert e.value.code == "UnknownPipeline" and e.value.kind == "server"
    with pytest.raises(dn.UsageError, match="pipeline 'svgf' has no parameter 'alpha'; valid names: alpha_colour") as e:
        conn.open_session(W, H, "svgf", channels=SVGF, parameters={"alpha": 0.2})
    assert e.value.code == "InvalidParameter" and e.value.field == "OPEN_SESSION.parameters[0].name"
    with pytest.raises(dn.UsageError, match="'atrous_iterations' of pipeline 'svgf' is 2.5, but must be an integer"):
        conn.open_session(W, H, "svgf", channels=SVGF, parameters={"atrous_iterations": 2.5})
    with pytest.raises(dn.UsageError, match="unknown channel 'colour'"):
        conn.open_session(W, H, "passthrough", channels=["colour"])
    with pytest.raises(dn.UsageError, match="format 'f64'"):
        conn.open_session(W, H, "passthrough", channels={"radiance": "f64"})
    with pytest.raises(dn.UsageError, match="does not take channel emission"):
        conn.open_session(W, H, "accumulate", channels=["radiance", "normal", "depth", "motion", "emission"])
    with pytest.raises(dn.ServerError, match="albedo") as e:  # svgf requires it
        conn.open_session(W, H, "svgf", channels=["radiance", "normal", "depth", "motion"])
    assert e.value.code == "MissingChannel"
    # The connection survives every refusal.
    with conn.open_session(W, H, "passthrough", channels=["radiance"]) as s:
        assert s.is_open


def test_camera_arguments_are_checked(conn):
    with conn.open_session(W, H, "passthrough", channels=["radiance"]) as s:
        f = {"radiance": np.zeros((H, W, 3), np.float32)}
        with pytest.raises(dn.UsageError, match=r"view: expected a 4x4 matrix .*got shape \(3, 3\)"):
            s.denoise(f, view=np.eye(3))
        with pytest.raises(dn.UsageError, match="motion='sideways'"):
            s.denoise(f, motion="sideways")
        with pytest.raises(dn.UsageError, match="prev_view and prev_projection go together"):
            s.denoise(f, prev_view=np.eye(4))
        out = s.denoise(f, view=np.eye(4), projection=np.eye(4), jitter=(0.25, -0.25), motion="to-next",
                        prev_view=np.eye(4), prev_projection=np.eye(4), prev_jitter=(0, 0))
        assert out.shape == (H, W, 3)


# ---- svgf: fp16 inputs, bad values --------------------------------------------------------------


def test_svgf_with_fp16_inputs(conn):
    rng = np.random.default_rng(8)
    with conn.open_session(W, H, "svgf", channels={k: "f16" for k in SVGF},
                           parameters={"alpha_colour": 0.1}) as s:
        for i in range(3):
            frame = {k: v.astype(np.float16) for k, v in still_scene(rng).items()}
            out = s.denoise(frame, reset=(i == 0))
            assert out.shape == (H, W, 3) and out.dtype == np.float32
            assert np.all(np.isfinite(out)) and np.all(out >= 0)
        # A still noisy wall: the filter lowers the variance of the uniform noise (1/12 per component).
        assert np.var(out) < np.var(frame["radiance"].astype(np.float32))


def test_svgf_survives_nan_and_inf(conn):
    rng = np.random.default_rng(9)
    with conn.open_session(W, H, "svgf", channels=SVGF) as s:
        s.denoise(still_scene(rng), reset=True)
        bad = still_scene(rng)
        bad["radiance"][4:12, 4:12] = np.nan
        bad["radiance"][20:24, 30:40] = np.inf
        bad["albedo"][0:6, 50:60] = np.nan
        bad["normal"][10:14, 10:20] = np.nan
        bad["depth"][30:, :8] = np.nan
        bad["motion"][:4, :4] = np.inf
        out = s.denoise(bad)
        assert np.all(np.isfinite(out))
        for _ in range(2):
            out = s.denoise(still_scene(rng))
            assert np.all(np.isfinite(out))


def test_module_constants():
    assert dn.CHANNELS["radiance"] == 3 and dn.CHANNELS["depth"] == 1 and dn.CHANNELS["motion"] == 2
    assert "output" not in dn.CHANNELS
    assert issubclass(dn.UsageError, dn.Error) and issubclass(dn.UsageError, ValueError)
    assert issubclass(dn.TimeoutError, dn.TransportError) and issubclass(dn.TimeoutError, TimeoutError)
    assert issubclass(dn.ServerError, dn.Error) and issubclass(dn.Error, RuntimeError)
