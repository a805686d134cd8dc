#!/usr/bin/env python3
"""dn preview started before its session (tests/preview/preview_key_file_test.py).

`dn preview --key-file F` starts first, before F exists, and serves the page
at once; F then names a session that is not open (as a file left by an
earlier run would), which dn preview reports and waits past. An owner
then opens a session and writes its key and id to F (as dnrender and
dn denoise --watch-key-file do); the page shows its frames. The page's
fit-to-window and 1:1 buttons size the canvases; when the session ends the
page keeps the last frame, marked ended, and dn preview keeps running; a
second owner's session then appears on the same page. Without -v dn preview
prints no line per frame.
Exit 0 pass, 1 fail, 77 skip (no browser).
"""
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from browser_preview_test import DevTools, Line, TIMEOUT_S, fail, find_browser  # noqa: E402

FRAMES = 4
WIDTH, HEIGHT = 96, 54
WINDOW_W, WINDOW_H = 800, 600


def wait_for(tools, expression, expected, what):
    deadline = time.monotonic() + TIMEOUT_S
    while True:
        value = tools.evaluate(expression)
        if value == expected:
            return
        if time.monotonic() > deadline:
            fail("%s: %s is %r, expected %r" % (what, expression, value, expected))
        time.sleep(0.1)


def canvas_rect(tools):
    return tools.evaluate("(r => [r.width, r.height])(document.getElementById('output').getBoundingClientRect())")


def wait_in_log(log_path, text, preview, what):
    deadline = time.monotonic() + TIMEOUT_S
    while text not in open(log_path).read():
        if preview.poll() is not None:
            fail("dn preview exited %d before %s" % (preview.returncode, what))
        if time.monotonic() > deadline:
            fail("timed out waiting for " + what)
        time.sleep(0.1)


def run_owner(streamer, url, key_file, work, tools, preview, log_path, name):
    """Starts an owner that writes the key file and, once dn preview shows its session, streams
    FRAMES frames (a watcher sees the frames after it attaches); returns (process, session id)."""
    owner = subprocess.Popen([streamer, url, "svgf", str(FRAMES), str(WIDTH), str(HEIGHT),
                              os.path.join(work, name + ".pfm"), key_file],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    out = Line(owner.stdout)
    session = out.until(r"^session (\d+) [0-9a-f]{32}$", what=name + "'s session").group(1)
    wait_in_log(log_path, "dn: showing session " + session, preview, "dn preview to attach to " + name + "'s session")
    owner.stdin.write(b"go\n")
    owner.stdin.flush()
    out.until(r"^done %d$" % FRAMES, what=name + "'s frames")
    wait_for(tools, "window.dnPreview.header && window.dnPreview.header.session", session,
             "the page shows " + name + "'s session")
    wait_for(tools, "window.dnPreview.frameIndex", FRAMES - 1, "the page shows " + name + "'s last frame")
    wait_for(tools, "window.dnPreview.status", "live", name + "'s session is live")
    return owner, session


def main():
    dnserver, dn, streamer = sys.argv[1:4]
    browser = find_browser()
    if not browser:
        print("SKIP: no chromium-headless-shell or chromium on PATH (scripts/setup.sh installs it)")
        return 77
    work = tempfile.mkdtemp(prefix="dn-preview-key-file-test-")
    children = []
    tools = None
    try:
        server = subprocess.Popen([dnserver, "--no-warm-up", "--listen", "tcp://127.0.0.1:0"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        children.append(server)
        port = Line(server.stderr).until(r"event=listen .*tcp://127\.0\.0\.1:(\d+)", what="dnserver's port").group(1)
        url = "tcp://127.0.0.1:" + port

        key_file = os.path.join(work, "watch.key")  # not there yet
        preview_log = open(os.path.join(work, "preview.log"), "w+")
        env = {k: v for k, v in os.environ.items() if k != "DN_WATCH_KEY"}
        preview = subprocess.Popen([dn, "preview", "--server", url, "--key-file", key_file, "--http", "127.0.0.1:0"],
                                   stdout=subprocess.PIPE, stderr=preview_log, env=env)
        children.append(preview)
        page_url = Line(preview.stdout).until(r"at (http://127\.0\.0\.1:\d+/)$", what="the preview URL").group(1)

        tools = DevTools(browser, os.path.join(work, "profile"))
        target_id = tools.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        tools.session = tools.call("Target.attachToTarget", {"targetId": target_id, "flatten": True})["sessionId"]
        tools.call("Emulation.setDeviceMetricsOverride",
                   {"width": WINDOW_W, "height": WINDOW_H, "deviceScaleFactor": 1, "mobile": False})
        tools.call("Page.navigate", {"url": page_url})
        wait_for(tools, "window.dnPreview && window.dnPreview.status", "waiting", "the page waits for a session")

        # As if left by an earlier run: a session that is not open on this server.
        with open(key_file + ".tmp", "w") as f:
            f.write("0123456789abcdef0123456789abcdef\nsession 1\n")
        os.chmod(key_file + ".tmp", 0o600)
        os.rename(key_file + ".tmp", key_file)
        wait_in_log(preview_log.name, "dn: session 1 named in %s cannot be watched" % key_file, preview,
                    "dn preview to report the closed session the key file names")
        if tools.evaluate("window.dnPreview.status") != "waiting":
            fail("the page stopped waiting after a closed session")

        owner, first = run_owner(streamer, url, key_file, work, tools, preview, preview_log.name, "owner 1")
        children.append(owner)

        # Fit to window: both canvases side by side fill the width, aspect kept; 1:1: image pixels.
        tools.evaluate("document.getElementById('zoom-fit').click()")
        w, h = canvas_rect(tools)
        print("fit: output canvas %.1f x %.1f in a %dx%d window" % (w, h, WINDOW_W, WINDOW_H), flush=True)
        if abs(2 * w - WINDOW_W) > 1 or abs(h * WIDTH - w * HEIGHT) > WIDTH:
            fail("fit to window shows the canvas at %.1f x %.1f (expected %.1f wide, aspect %d:%d)" %
                 (w, h, WINDOW_W / 2, WIDTH, HEIGHT))
        if tools.evaluate("document.documentElement.scrollWidth") > WINDOW_W:
            fail("fit to window overflows the window's width")
        tools.evaluate("document.getElementById('zoom-1to1').click()")
        w, h = canvas_rect(tools)
        if (w, h) != (WIDTH, HEIGHT):
            fail("1:1 shows the canvas at %s x %s, expected %d x %d" % (w, h, WIDTH, HEIGHT))

        # The session ends: the page keeps its last frame and says so; dn preview stays.
        owner.stdin.close()
        if owner.wait(timeout=60) != 0:
            fail("owner 1 exited %d" % owner.returncode)
        wait_for(tools, "window.dnPreview.status", "ended", "the page marks the session ended")
        status = tools.evaluate("document.getElementById('status').textContent")
        if ("session %s ended after %d frames" % (first, FRAMES)) not in status:
            fail("the page's status after the end: " + status)
        lit = tools.evaluate("(c => c.getContext('2d').getImageData(0, 0, c.width, c.height).data"
                             ".reduce((s, v) => s + v, 0))(document.getElementById('output'))")
        if tools.evaluate("window.dnPreview.frameIndex") != FRAMES - 1 or not lit:
            fail("the page lost the last frame when the session ended")
        time.sleep(1.0)
        if preview.poll() is not None:
            fail("dn preview exited %d when the session ended" % preview.returncode)

        # The next session written to the key file appears on the same page.
        owner2, second = run_owner(streamer, url, key_file, work, tools, preview, preview_log.name, "owner 2")
        children.append(owner2)
        if second == first:
            fail("the second owner got the first session's id")
        owner2.stdin.close()
        owner2.wait(timeout=60)
        wait_for(tools, "window.dnPreview.status", "ended", "the page marks the second session ended")

        preview_log.seek(0)
        log = preview_log.read()
        print(log, end="", flush=True)
        if "dn: frame " in log:
            fail("dn preview printed per-frame lines without -v")
        for session in (first, second):
            if "dn: showing session " + session not in log:
                fail("dn preview did not report showing session " + session)
        print("PASS", flush=True)
        return 0
    finally:
        if tools:
            tools.close()
        for child in children:
            if child.poll() is None:
                child.kill()
                child.wait()
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
