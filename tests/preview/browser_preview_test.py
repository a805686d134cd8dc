#!/usr/bin/env python3
"""dn preview in a real browser (Debian's chromium-headless-shell).

Starts dnserver, a streaming owner that shares its input (stream_and_hold),
`dn preview` and, as the independent witness, `dn watch` writing float PFMs.
Loads the page in headless Chromium over the DevTools protocol (on a pipe, so
the test needs no WebSocket client), waits until the page shows the last
frame, takes a screenshot, and checks:
  - the denoised canvas equals the frame `dn watch` received, tone-mapped here
    (ACES fit + sRGB, written from the formulas, not from dn's code), within
    one 8-bit step;
  - the noisy-input canvas equals the radiance the owner sent;
  - the page names the pipeline, the frame index and per-pass timings;
  - when the owner closes the session, dn watch exits 0 and the page keeps the
    last frame, marked ended, with dn preview still serving it.
Exit 0 pass, 1 fail, 77 skip (no browser).
"""
import base64
import json
import math
import os
import re
import select
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

FRAMES = 6
WIDTH, HEIGHT = 96, 54
TIMEOUT_S = 120.0


def fail(message):
    print("FAIL: " + message, flush=True)
    sys.exit(1)


def find_browser():
    for name in ("chromium-headless-shell", "chromium", "chromium-browser"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Line:
    """Reads a child's stdout/stderr line by line with a deadline."""

    def __init__(self, stream):
        self.stream = stream
        self.buffer = b""

    def until(self, pattern, timeout_s=TIMEOUT_S, what=""):
        deadline = time.monotonic() + timeout_s
        regex = re.compile(pattern)
        while True:
            while b"\n" in self.buffer:
                line, self.buffer = self.buffer.split(b"\n", 1)
                text = line.decode(errors="replace")
                m = regex.search(text)
                if m:
                    return m
            left = deadline - time.monotonic()
            if left <= 0:
                fail("timed out waiting for " + (what or pattern))
            ready, _, _ = select.select([self.stream], [], [], left)
            if ready:
                chunk = os.read(self.stream.fileno(), 65536)
                if not chunk:
                    fail("stream ended while waiting for " + (what or pattern))
                self.buffer += chunk


def aces(x):
    """Narkowicz 2015 ACES fit, clamped to [0, 1]; NaN, negatives -> 0."""
    if not x > 0.0:
        return 0.0
    if math.isinf(x):
        return 1.0
    y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
    return min(max(y, 0.0), 1.0)


def srgb8(x):
    x = min(max(x, 0.0), 1.0)
    v = 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1.0 / 2.4) - 0.055
    return int(math.floor(v * 255.0 + 0.5))


def read_pfm(path):
    with open(path, "rb") as f:
        data = f.read()
    header = re.match(rb"PF\s+(\d+)\s+(\d+)\s+(\S+)\s", data)
    if not header:
        fail(path + " is not a colour PFM")
    w, h, scale = int(header.group(1)), int(header.group(2)), float(header.group(3))
    fmt = ("<" if scale < 0 else ">") + "f" * (w * h * 3)
    values = struct.unpack(fmt, data[header.end():header.end() + w * h * 12])
    rows = [values[y * w * 3:(y + 1) * w * 3] for y in range(h)]
    rows.reverse()  # PFM stores the bottom row first
    return w, h, [v for row in rows for v in row]


def decode_png(data):
    """8-bit RGB/RGBA, non-interlaced PNG -> (w, h, channels, bytes)."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail("screenshot is not a PNG")
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            w, h, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour not in (2, 6) or interlace:
                fail("unexpected PNG format (depth %d, colour %d, interlace %d)" % (depth, colour, interlace))
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = w * channels
    out = bytearray(stride * h)
    prev = bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[i] = (line[i] + pred) & 255
        out[y * stride:(y + 1) * stride] = line
        prev = line
    return w, h, channels, bytes(out)


class DevTools:
    """Chrome DevTools Protocol over --remote-debugging-pipe (fd 3 in, fd 4 out, NUL-separated JSON)."""

    def __init__(self, browser, profile_dir):
        to_browser_r, self.to_browser = os.pipe()
        self.from_browser, from_browser_w = os.pipe()

        def wire_fds():
            os.dup2(to_browser_r, 3)
            os.dup2(from_browser_w, 4)

        args = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--remote-debugging-pipe",
                "--force-color-profile=srgb", "--force-device-scale-factor=1", "--no-first-run",
                "--user-data-dir=" + profile_dir, "--window-size=800,600", "about:blank"]
        self.process = subprocess.Popen(args, preexec_fn=wire_fds, close_fds=False,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.next_id = 0
        self.buffer = b""
        self.session = None

    def call(self, method, params=None, timeout_s=TIMEOUT_S):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if self.session:
            message["sessionId"] = self.session
        os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + timeout_s
        while True:
            while b"\0" in self.buffer:
                raw, self.buffer = self.buffer.split(b"\0", 1)
                reply = json.loads(raw)
                if reply.get("id") == self.next_id:
                    if "error" in reply:
                        fail("DevTools %s: %s" % (method, reply["error"]))
                    return reply["result"]
            left = deadline - time.monotonic()
            if left <= 0:
                fail("DevTools %s: no reply" % method)
            ready, _, _ = select.select([self.from_browser], [], [], left)
            if ready:
                chunk = os.read(self.from_browser, 1 << 20)
                if not chunk:
                    fail("the browser exited during " + method)
                self.buffer += chunk

    def evaluate(self, expression):
        result = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True})
        return result["result"].get("value")

    def close(self):
        self.process.kill()
        self.process.wait()


def compare(name, png, rect, expected_rgb8):
    """Max abs difference between a canvas's screenshot pixels and the expected RGB8."""
    w, h, channels, pixels = png
    x0, y0 = int(round(rect["x"])), int(round(rect["y"]))
    worst, worst_at = 0, None
    for y in range(HEIGHT):
        for x in range(WIDTH):
            at = ((y0 + y) * w + (x0 + x)) * channels
            for c in range(3):
                d = abs(pixels[at + c] - expected_rgb8[(y * WIDTH + x) * 3 + c])
                if d > worst:
                    worst, worst_at = d, (x, y, c)
    print("%s: max |screenshot - expected| = %d (8-bit steps)%s" %
          (name, worst, "" if worst_at is None else " at x,y,c = %s" % (worst_at,)), flush=True)
    if worst > 1:
        fail("%s canvas differs from the expected pixels by %d steps at %s" % (name, worst, worst_at))


def main():
    dnserver, dn, streamer = sys.argv[1:4]
    browser = find_browser()
    if not browser:
        print("SKIP: no chromium-headless-shell or chromium on PATH (scripts/setup.sh installs it)")
        return 77
    work = tempfile.mkdtemp(prefix="dn-preview-test-")
    children = []
    try:
        server = subprocess.Popen([dnserver, "--no-warm-up", "--listen", "tcp://127.0.0.1:0"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        children.append(server)
        port = Line(server.stderr).until(r"event=listen .*tcp://127\.0\.0\.1:(\d+)", what="dnserver's port").group(1)
        url = "tcp://127.0.0.1:" + port

        last_input = os.path.join(work, "last_input.pfm")
        owner = subprocess.Popen([streamer, url, "svgf", str(FRAMES), str(WIDTH), str(HEIGHT), last_input],
                                 stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        children.append(owner)
        owner_out = Line(owner.stdout)
        session, key = owner_out.until(r"^session (\d+) ([0-9a-f]{32})$", what="the session id").groups()

        target = ["--server", url, "--session", session]
        env = dict(os.environ, DN_WATCH_KEY=key)  # the key in the environment, not on the command line
        preview = subprocess.Popen([dn, "preview", *target, "--http", "127.0.0.1:0", "--quiet"],
                                   stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env)
        children.append(preview)
        page_url = Line(preview.stdout).until(r"at (http://127\.0\.0\.1:\d+/)$", what="the preview URL").group(1)
        watch = subprocess.Popen([dn, "watch", *target, "--output", os.path.join(work, "w_%04d.pfm")],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
        children.append(watch)
        Line(watch.stderr).until(r"watching session", what="dn watch to attach")

        owner.stdin.write(b"go\n")
        owner.stdin.flush()
        owner_out.until(r"^done %d$" % FRAMES, what="the owner's frames")
        last = FRAMES - 1
        watched = os.path.join(work, "w_%04d.pfm" % last)
        deadline = time.monotonic() + TIMEOUT_S
        while not os.path.exists(watched):
            if time.monotonic() > deadline:
                fail("dn watch did not write frame %d" % last)
            time.sleep(0.1)
        time.sleep(0.2)  # let the writer finish the file

        tools = DevTools(browser, os.path.join(work, "profile"))
        try:
            target_id = tools.call("Target.createTarget", {"url": "about:blank"})["targetId"]
            tools.session = tools.call("Target.attachToTarget", {"targetId": target_id, "flatten": True})["sessionId"]
            tools.call("Emulation.setDeviceMetricsOverride",
                       {"width": 800, "height": 600, "deviceScaleFactor": 1, "mobile": False})
            tools.call("Page.navigate", {"url": page_url})
            deadline = time.monotonic() + TIMEOUT_S
            while tools.evaluate("window.dnPreview ? window.dnPreview.frameIndex : -2") != last:
                if time.monotonic() > deadline:
                    fail("the page never showed frame %d" % last)
                time.sleep(0.1)
            summary = tools.evaluate("document.getElementById('summary').textContent")
            timing_rows = tools.evaluate("document.querySelectorAll('#timings tr').length")
            print("page: %s; %d timing rows" % (summary, timing_rows), flush=True)
            if "svgf" not in summary or ("frame %d" % last) not in summary or "session " + session not in summary:
                fail("the page does not name the pipeline, frame and session: " + summary)
            if timing_rows < 3:
                fail("the page lists %d per-pass timings" % timing_rows)
            rects = json.loads(tools.evaluate(
                "JSON.stringify(['output','input'].map(id => document.getElementById(id).getBoundingClientRect()))"))
            if tools.evaluate("document.getElementById('input-panel').hidden"):
                fail("the page hides the noisy input the owner shared")
            shot = tools.call("Page.captureScreenshot", {"format": "png", "fromSurface": True})
            png = decode_png(base64.b64decode(shot["data"]))

            owner.stdin.close()  # the owner closes its session: dn watch ends, the page stays
            for name, child in (("owner", owner), ("dn watch", watch)):
                try:
                    code = child.wait(timeout=60)
                except subprocess.TimeoutExpired:
                    fail(name + " did not exit after the session closed")
                if code != 0:
                    fail("%s exited %d" % (name, code))
            deadline = time.monotonic() + TIMEOUT_S
            while tools.evaluate("window.dnPreview.status") != "ended":
                if time.monotonic() > deadline:
                    fail("the page never marked the session ended")
                time.sleep(0.1)
            status = tools.evaluate("document.getElementById('status').textContent")
            print("page after the end: " + status, flush=True)
            if "session %s ended after %d frames" % (session, FRAMES) not in status:
                fail("the page's status after the end: " + status)
            if tools.evaluate("window.dnPreview.frameIndex") != last:
                fail("the page lost the last frame when the session ended")
            if preview.poll() is not None:
                fail("dn preview exited %d when the session ended (the page would go)" % preview.returncode)
        finally:
            tools.close()

        w, h, denoised = read_pfm(watched)
        if (w, h) != (WIDTH, HEIGHT):
            fail("dn watch wrote %dx%d" % (w, h))
        compare("denoised", png, rects[0], [srgb8(aces(v)) for v in denoised])
        _, _, noisy = read_pfm(last_input)
        compare("noisy input", png, rects[1], [srgb8(aces(v)) for v in noisy])

        print("PASS", flush=True)
        return 0
    finally:
        for child in children:
            if child.poll() is None:
                child.kill()
                child.wait()
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
