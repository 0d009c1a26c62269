#!/usr/bin/env python3
"""Writes a synthetic points file (view,X,Y,Z,u,v) of a 9x6 board seen by a known camera
(fx=fy=820, cx=321.3, cy=238.7, k1=-0.12, k2=0.05, p1=0.0007, p2=-0.0004, 640x480) with
0.1 px noise, seed fixed. Usage: make_calib_points.py OUT.csv"""
import math
import random
import sys

FX, FY, CX, CY, K1, K2, P1, P2 = 820, 820, 321.3, 238.7, -0.12, 0.05, 0.0007, -0.0004


def rot(ax, ay, az):
    def mul(a, b):
        return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    cx, sx, cy, sy, cz, sz = math.cos(ax), math.sin(ax), math.cos(ay), math.sin(ay), math.cos(az), math.sin(az)
    return mul(mul([[1, 0, 0], [0, cx, -sx], [0, sx, cx]], [[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]]),
               [[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])


def project(p):
    x, y = p[0] / p[2], p[1] / p[2]
    r2 = x * x + y * y
    rad = 1 + K1 * r2 + K2 * r2 * r2
    xd = x * rad + 2 * P1 * x * y + P2 * (r2 + 2 * x * x)
    yd = y * rad + P1 * (r2 + 2 * y * y) + 2 * P2 * x * y
    return FX * xd + CX, FY * yd + CY


def main():
    rng = random.Random(5)
    rows, view = [], 0
    while view < 15:
        R = rot(math.pi + 0.5 * rng.uniform(-1, 1), 0.5 * rng.uniform(-1, 1), 0.3 * rng.uniform(-1, 1))
        t = (-0.1 + 0.08 * rng.uniform(-1, 1), 0.06 + 0.05 * rng.uniform(-1, 1), 0.7 + 0.2 * rng.uniform(-1, 1))
        pts, ok = [], True
        for r in range(6):
            for c in range(9):
                X = (0.025 * c, 0.025 * r, 0.0)
                P = [sum(R[i][k] * X[k] for k in range(3)) + t[i] for i in range(3)]
                u, v = project(P)
                u += rng.gauss(0, 0.1)
                v += rng.gauss(0, 0.1)
                ok = ok and P[2] > 0 and 0 < u < 639 and 0 < v < 479
                pts.append(f"{view},{X[0]:.4f},{X[1]:.4f},0,{u:.5f},{v:.5f}")
        if ok:
            rows += pts
            view += 1
    with open(sys.argv[1], "w") as f:
        f.write("view,X,Y,Z,u,v\n" + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
