"""Where the kincal LCM Python package is: shared by the scripts beside this file.

use_lcm_types(path) puts the first folder holding the `kincal` package on sys.path: the
given path, $KINCAL_LCM_TYPES, a build tree's build/lcmgen/python, or an install's
share/kincal/python. The caller then imports the types it needs from `kincal`.
"""

import os
import sys


def use_lcm_types(path=None):
    here = os.path.dirname(os.path.abspath(__file__))
    candidates = (path, os.environ.get("KINCAL_LCM_TYPES"), os.path.join(here, "..", "build", "lcmgen", "python"),
                  os.path.join(here, "..", "python"))
    for c in candidates:
        if c and os.path.isdir(os.path.join(c, "kincal")):
            if c not in sys.path:
                sys.path.insert(0, c)
            return c
    return None
