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


# The kincal messages, by name (lcm/*.lcm).
MESSAGE_NAMES = ("preview_t", "frame_t", "markers_t", "pose_t", "params_t", "calibration_t",
                 "model_check_t", "health_t", "guidance_t", "controls_t", "run_t", "truth_t")


def message_types():
    """{LCM fingerprint: class} of the kincal messages (use_lcm_types first): how a reader
    knows a message's type whatever its channel is called."""
    import kincal
    out = {}
    for name in MESSAGE_NAMES:
        cls = getattr(kincal, name, None)
        if cls is not None:
            out[cls._get_packed_fingerprint()] = cls
    return out
