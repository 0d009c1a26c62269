"""Replays tests/data/golden_replay.lcm through kincald and compares what it publishes with
what the same log held when it was recorded: every pose, markers, params, model-check and
calibration event, stamp and bytes, must be equal. A refactoring must leave it passing;
it guards against change, not against error (the other tests judge against the truth).

Recorded 2026-11-23 before the daemon was split into stages; re-recorded 2026-11-24 when
the filter stage's behaviour changed on purpose (issue 15: adaptive noise, robust updates,
honest status, pose covariance calibrated to the residuals,
model_check_t schema 2), and 2026-11-26 when the batch tier came (issue 31: params_t
schema 3 with its source, STATUS_CONVERGED only when the filter agrees with a batch
calibration, KINCAL_CALIBRATION compared too, less its wall time), each time by replaying
the previous golden log through the new binary, so the log is the code's own output:
  kincald -c tests/data/kincald_golden.yaml --replay OLD --fast --record NEW --lcm-url memq://

  check_golden_replay.py KINCALD CONFIG GOLDEN_LOG LCMGEN_PYTHON SCRATCH_DIR
"""
import collections
import os
import subprocess
import sys

import lcm

TYPES = {}  # {LCM fingerprint: class}, filled in main()
OUTPUTS = ["KINCAL_POSE", "KINCAL_MARKERS", "KINCAL_PARAMS", "KINCAL_MODEL_CHECK",
           "KINCAL_CALIBRATION"]


def decoded(data):
    """The message in `data`, its type known by its LCM fingerprint (as the page, the MCAP
    export and the SIGKILL check read logs), or None when no kincal type has it."""
    cls = TYPES.get(data[:8])
    return cls.decode(data) if cls is not None else None


def normalised(data):
    """The bytes that must replay identically: a batch calibration less its wall time."""
    m = decoded(data)
    if m is None or type(m).__name__ != "calibration_t":
        return data
    m.compute_s = 0.0
    return m.encode()


def load(path):
    events = collections.defaultdict(list)
    for e in lcm.EventLog(path, "r"):
        events[e.channel].append((e.timestamp, normalised(e.data)))
    return events


def describe(data):
    """The decoded message, for a readable failure."""
    try:
        m = decoded(data)
        if m is None:
            return f"<{len(data)} bytes of no kincal type>"
        return {k: getattr(m, k) for k in m.__slots__ if k not in ("covariance",)}
    except Exception as e:  # the bytes differ so much that they do not decode
        return f"<{len(data)} bytes, undecodable: {e}>"


def main():
    global TYPES
    kincald, config, golden, lcmgen_python, scratch = sys.argv[1:6]
    sys.path.insert(0, lcmgen_python)
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scripts"))
    from kincal_lcm_types import message_types
    TYPES = message_types()
    os.makedirs(scratch, exist_ok=True)
    out = os.path.join(scratch, "replayed.lcm")
    if os.path.exists(out):
        os.remove(out)
    subprocess.run([kincald, "-c", config, "--replay", golden, "--fast", "--record", out,
                    "--lcm-url", "memq://", "-q"], check=True)
    want, got = load(golden), load(out)
    failures = 0
    for ch in OUTPUTS:
        a, b = want.get(ch, []), got.get(ch, [])
        if not a:
            print(f"golden_replay: the golden log has no {ch} events")
            failures += 1
            continue
        if len(a) != len(b):
            print(f"golden_replay: {ch}: {len(b)} events, the golden log has {len(a)}")
            failures += 1
        for k, (ea, eb) in enumerate(zip(a, b)):
            if ea != eb:
                print(f"golden_replay: {ch} event {k} differs:\n  golden   {ea[0]} {describe(ea[1])}\n"
                      f"  replayed {eb[0]} {describe(eb[1])}")
                failures += 1
                break
        if len(a) == len(b) and a == b:
            print(f"{ch}: {len(a)} events equal, stamps and bytes")
    if failures:
        print(f"golden_replay: {failures} channel(s) differ")
        return 1
    print("golden_replay: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
