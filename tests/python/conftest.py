"""Fixtures of the dn Python module's tests (ctest python_bindings).

ctest passes the paths through the environment (tests/python/CMakeLists.txt):
PYTHONPATH (the built module's directory), DN_DNSERVER (the dnserver binary),
DN_DN (the dn tool) and DN_SOURCE_DIR (the repository). By hand:

    PYTHONPATH=build/python DN_DNSERVER=build/server/dnserver DN_DN=build/client/dn \
        python3 -m pytest -q tests/python
"""

import os
import shutil
import signal
import subprocess
import tempfile
import threading
import time

import pytest

SOURCE_DIR = os.environ.get("DN_SOURCE_DIR") or os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "blender: runs examples/blender/denoise_render.py inside Blender (ctest python_blender_example)")


def _binary(env, default):
    path = os.environ.get(env) or os.path.join(SOURCE_DIR, "build", default)
    if not os.access(path, os.X_OK):
        pytest.fail("%s: %s is not an executable; set %s (ctest does)" % (env, path, env))
    return path


class Server:
    """A dnserver on a private Unix socket, for the whole test session."""

    def __init__(self):
        self.dir = tempfile.mkdtemp(prefix="dn-py-")  # short: a socket path is at most 107 bytes
        self.socket = os.path.join(self.dir, "dn.sock")
        self.url = "unix://" + self.socket
        self.log = []
        self._ready = threading.Event()
        # No warm-up: it compiles every pipeline up front; the tests open only a few.
        self.proc = subprocess.Popen([_binary("DN_DNSERVER", "server/dnserver"), "--no-warm-up", "--listen", self.url],
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace")
        # The log is drained for the server's whole life, so a full pipe never blocks it.
        self._reader = threading.Thread(target=self._drain, daemon=True)
        self._reader.start()
        if not self._ready.wait(120) or self.proc.poll() is not None:
            self.stop()
            raise RuntimeError("dnserver did not become ready:\n" + "".join(self.log))

    def _drain(self):
        for line in self.proc.stdout:
            self.log.append(line)
            if "event=ready" in line:
                self._ready.set()
        self._ready.set()  # EOF: the server exited; __init__ reports it

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(5)
        shutil.rmtree(self.dir, ignore_errors=True)


@pytest.fixture(scope="session")
def server():
    s = Server()
    yield s
    s.stop()


@pytest.fixture
def conn(server):
    import dn
    with dn.connect(server.url, client_name="pytest") as c:
        yield c


@pytest.fixture(scope="session")
def dn_tool():
    return _binary("DN_DN", "client/dn")
