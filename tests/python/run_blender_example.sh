#!/bin/sh
# ctest python_blender_example: runs the pytest tests marked `blender`
# (test_blender_example.py) when Blender is installed, else exits 77 (skipped).
#   run_blender_example.sh PYTHON TESTS_DIR
if ! command -v blender >/dev/null 2>&1; then
  echo "python_blender_example: skipped: blender is not on PATH (apt-get install blender to run examples/blender/denoise_render.py)"
  exit 77
fi
exec "$1" -m pytest -q -p no:cacheprovider -m blender "$2"
