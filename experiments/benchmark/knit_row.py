#!/usr/bin/env python3
"""One knit.csv row of knit_atol.sh from a `knitsim knit` output folder and the reference's.

    knit_row.py RUN_DIR REFERENCE_DIR CASE REPEAT      (prints the row)
    knit_row.py --header                               (prints the header)

dx_max_over_r: max over all interlacing points of |x - x_ref| / r, as written in points.csv.
shape_dx_over_r: the same after the rigid motion that best maps the run onto the reference
(centroids matched, rotation by Gauss-Newton on the rotation vector). The knit network is free
(no pins, no gravity), so its steady state is unique only up to a rigid motion; the integrators
conserve momentum (the centroids agree to ~1e-12 r) but implicit-euler's 1 s steps turn the
40 x 40 chart by 2.2e-4 rad about z, i.e. up to 0.046 r at its edge, which is no shape error.
"""
import csv
import json
import math
import os
import sys

HEADER = ("case,integrator,rtol,atol,velocity_atol,repeat,status,steps,lin_setups,nonlin_iters,"
          "t_final,residual,cpu_seconds,dx_max_over_r,shape_dx_over_r,newton_solver,"
          "factorisations,lin_iters")


def points(folder):
    return [[float(r["x"]), float(r["y"]), float(r["z"])]
            for r in csv.DictReader(open(os.path.join(folder, "points.csv")))]


def centred(a):
    c = [sum(p[i] for p in a) / len(a) for i in range(3)]
    return [[p[i] - c[i] for i in range(3)] for p in a]


def cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def solve3(m, b):  # Gauss-Jordan with partial pivoting
    a = [m[i][:] + [b[i]] for i in range(3)]
    for c in range(3):
        p = max(range(c, 3), key=lambda i: abs(a[i][c]))
        a[c], a[p] = a[p], a[c]
        for i in range(3):
            if i != c:
                f = a[i][c] / a[c][c]
                a[i] = [a[i][j] - f * a[c][j] for j in range(4)]
    return [a[i][3] / a[i][i] for i in range(3)]


def rotate(w, p):  # Rodrigues: by |w| rad about w / |w|
    t = math.sqrt(sum(x * x for x in w))
    if t == 0.0:
        return p[:]
    k = [x / t for x in w]
    c, s = math.cos(t), math.sin(t)
    kp, kd = cross(k, p), sum(k[i] * p[i] for i in range(3))
    return [p[i] * c + kp[i] * s + k[i] * kd * (1.0 - c) for i in range(3)]


def shape_dx(a, b):
    """max_k |Q_k - R P_k|, P and Q the centred point sets, R the least-squares rotation."""
    p, q = centred(a), centred(b)
    for _ in range(4):  # Gauss-Newton: min sum |q - p - w x p|^2 over w, then rotate p by w
        m = [[0.0] * 3 for _ in range(3)]
        rhs = [0.0] * 3
        for pk, qk in zip(p, q):
            pp = sum(x * x for x in pk)
            for i in range(3):
                for j in range(3):
                    m[i][j] += (pp if i == j else 0.0) - pk[i] * pk[j]
            c = cross(pk, [qk[i] - pk[i] for i in range(3)])
            rhs = [rhs[i] + c[i] for i in range(3)]
        w = solve3(m, rhs)
        p = [rotate(w, pk) for pk in p]
    return max(math.dist(pk, qk) for pk, qk in zip(p, q))


def row(run, ref, case, repeat):
    s = json.load(open(os.path.join(run, "summary.json")))
    o, st = s["options"], s["stats"]
    dx = shape = ""
    if os.path.abspath(run) != os.path.abspath(ref):
        a, b, r = points(run), points(ref), s["params"]["loop_radius"]
        dx = repr(max(math.dist(p, q) for p, q in zip(a, b)) / r)
        shape = repr(shape_dx(a, b) / r)
    return ",".join([case, s["integrator"], repr(o["rtol"]), repr(o["atol"]),
                     repr(o["velocity_atol"]), repeat, s["status"], str(st["steps"]),
                     str(st["lin_setups"]), str(st["nonlin_iters"]), repr(s["t_final"]),
                     repr(s["residual"]), repr(st["cpu_seconds"]), dx, shape,
                     o.get("newton_solver", ""), str(st.get("factorisations", "")),
                     str(st.get("lin_iters", ""))])


if __name__ == "__main__":
    if sys.argv[1:] == ["--header"]:
        print(HEADER)
    else:
        print(row(*sys.argv[1:5]))
