"""Every ```python block of docs/client.md and README.md is a complete
script: each runs here, from the repository root, against the fixture
server (its address in $DN_SERVER) and must exit 0."""

import os
import re
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR

PAGES = ["docs/client.md", "README.md"]


def blocks():
    found = []
    for page in PAGES:
        with open(os.path.join(SOURCE_DIR, page), encoding="utf-8") as f:
            text = f.read()
        for m in re.finditer(r"^```python\n(.*?)^```", text, re.S | re.M):
            line = text.count("\n", 0, m.start()) + 2
            found.append(pytest.param(page, line, m.group(1), id="%s:%d" % (page, line)))
    return found


def test_the_pages_have_python_examples():
    assert {p.values[0] for p in blocks()} == set(PAGES)


@pytest.mark.parametrize("page,line,code", blocks())
def test_python_example_runs(page, line, code, server, tmp_path):
    script = tmp_path / "example.py"
    # Blank lines up to the block's first line, so a traceback names the page's line.
    script.write_text("\n" * (line - 1) + code)
    env = dict(os.environ, DN_SERVER=server.url)
    p = subprocess.run([sys.executable, str(script)], cwd=SOURCE_DIR, env=env, capture_output=True, text=True,
                       timeout=240)
    assert p.returncode == 0, "%s:%d exited %d\n%s%s" % (page, line, p.returncode, p.stdout, p.stderr)


def test_readme_python_example_prints_what_it_did_with_the_python_the_readme_names(server, tmp_path):
    """README.md names the interpreter its example runs with; it must be the one
    the module was built for (the one running these tests), and the example
    must say what it did."""
    with open(os.path.join(SOURCE_DIR, "README.md"), encoding="utf-8") as f:
        text = f.read()
    named = re.search(r"^PYTHONPATH=build/python (\S+) example\.py", text, re.M)
    assert named, "README.md names no interpreter for its Python example (PYTHONPATH=build/python PYTHON example.py)"
    python = named.group(1)
    assert os.path.realpath(python) == os.path.realpath(sys.executable), \
        "README.md runs the example with %s, the module is built for %s" % (python, sys.executable)
    (page, line, code), = [p.values for p in blocks() if p.values[0] == "README.md"]
    script = tmp_path / "example.py"
    script.write_text(code)
    p = subprocess.run([python, str(script)], cwd=SOURCE_DIR, env=dict(os.environ, DN_SERVER=server.url),
                       capture_output=True, text=True, timeout=240)
    assert p.returncode == 0, "README.md:%d exited %d\n%s%s" % (line, p.returncode, p.stdout, p.stderr)
    assert re.fullmatch(r"denoised a 64x36 frame with svgf: \(36, 64, 3\) float32, mean \d\.\d{3}\n", p.stdout), p.stdout
