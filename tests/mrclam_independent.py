"""An independent fit of an MR.CLAM robot's turn-rate gain and command delay, written apart
from kincal (numpy only), for tests/check_mrclam.py to judge `kincal analyze` by.

The heading change over a window depends on the commands only through the turn rate:
dtheta = k_omega * integral of omega_cmd(t - delay). Over 1 s windows of the motion-capture
heading (unwrapped), the gain is linear least squares for each delay on a 5 ms grid; the
delay is the one with the least residual. Nothing here reads kincal's code or output."""
import numpy as np


def load(path, columns):
    rows = []
    with open(path, encoding="utf-8-sig") as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                rows.append([float(x) for x in line.split()[:columns]])
    return np.array(rows)


def command_integral(t_cmd, w_cmd, a, b):
    """Integral of the zero-order-held command over [a, b] for arrays a, b."""
    # Cumulative integral at the command times, then interpolate (exact for a step signal
    # between samples when evaluated through the held value).
    dt = np.diff(t_cmd)
    cum = np.concatenate([[0.0], np.cumsum(w_cmd[:-1] * dt)])

    def at(x):
        i = np.clip(np.searchsorted(t_cmd, x, side="right") - 1, 0, len(t_cmd) - 1)
        return cum[i] + w_cmd[i] * (x - t_cmd[i])

    return at(b) - at(a)


def fit(dataset, robot, window_s=1.0, stride_s=0.5, max_delay_s=0.4):
    odo = load(f"{dataset}/Robot{robot}_Odometry.dat", 3)
    gt = load(f"{dataset}/Robot{robot}_Groundtruth.dat", 4)
    t_cmd, w_cmd = odo[:, 0], odo[:, 2]
    t_gt, th = gt[:, 0], np.unwrap(gt[:, 3])
    starts = np.arange(max(t_gt[0], t_cmd[0]) + max_delay_s, min(t_gt[-1], t_cmd[-1]) - window_s,
                       stride_s)
    th0 = np.interp(starts, t_gt, th)
    th1 = np.interp(starts + window_s, t_gt, th)
    # Windows across a gap in the motion capture are left out.
    i0 = np.searchsorted(t_gt, starts)
    i1 = np.searchsorted(t_gt, starts + window_s)
    gaps = np.array([np.max(np.diff(t_gt[a:b + 1])) if b > a else np.inf for a, b in zip(i0, i1)])
    keep = gaps < 0.1
    dth = (th1 - th0)[keep]
    best = None
    for d in np.arange(0.0, max_delay_s + 1e-9, 0.005):
        u = command_integral(t_cmd, w_cmd, starts[keep] - d, starts[keep] + window_s - d)
        k = float(np.dot(u, dth) / np.dot(u, u))
        r = float(np.sum((dth - k * u) ** 2))
        if best is None or r < best[2]:
            best = (k, d, r)
    return {"k_omega": best[0], "delay_s": best[1], "windows": int(np.sum(keep))}


if __name__ == "__main__":
    import sys
    print(fit(sys.argv[1], int(sys.argv[2])))
