"""The dn Python module from Blender, whose Python does not read PYTHONPATH."""

import os
import sys


def import_dn(directories):
    """Imports dn, first adding each existing directory of `directories` to sys.path;
    ImportError saying how to build it otherwise."""
    for d in directories:
        if d and os.path.isdir(d) and os.path.abspath(d) not in sys.path:
            sys.path.insert(0, os.path.abspath(d))
    try:
        import dn
    except ImportError as e:
        raise ImportError("cannot import the dn module (%s): build it (cmake --build build --target dn_python) "
                          "and give its directory" % e) from e
    return dn
