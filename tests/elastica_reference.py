#!/usr/bin/python3
"""Reference values for tests/test_yarn_rods.cpp: the cantilevered elastica under a dead tip load.

B theta'' = -P cos(theta), theta(0) = 0 (clamped), theta'(L) = 0 (free tip), theta the slope below
the horizontal; in units of L with alpha = P L^2 / B. Solved twice, by collocation (solve_bvp) and
by shooting on theta'(0) (DOP853); both print the tip (x/L, y/L, theta). For alpha = 1 the
deflection 0.30172 is Bisshopp & Drucker's (1945, Quart. Appl. Math. 3, 272-275).
Run: /usr/bin/python3 tests/elastica_reference.py  (about a second)
"""
import numpy as np
from scipy.integrate import solve_bvp, solve_ivp
from scipy.optimize import brentq


def rhs(alpha):
    return lambda s, y: np.vstack([y[1], -alpha * np.cos(y[0]), np.cos(y[0]), np.sin(y[0])])


def collocation(alpha):
    s = np.linspace(0.0, 1.0, 201)
    y = np.zeros((4, s.size))
    y[2] = s
    bc = lambda ya, yb: np.array([ya[0], yb[1], ya[2], ya[3]])
    r = solve_bvp(rhs(alpha), bc, s, y, tol=1e-12, max_nodes=100000)
    t, _, x, z = r.sol(1.0)
    return x, z, t


def shooting(alpha):
    def end(k0):
        f = lambda s, y: [y[1], -alpha * np.cos(y[0]), np.cos(y[0]), np.sin(y[0])]
        r = solve_ivp(f, [0.0, 1.0], [0.0, k0, 0.0, 0.0], rtol=1e-13, atol=1e-14, method="DOP853")
        return r.y[:, -1]
    k0 = brentq(lambda k: end(k)[1], 0.0, alpha, xtol=1e-15)
    t, _, x, z = end(k0)
    return x, z, t


for alpha in (1.0, 2.0, 3.0):
    for name, solve in (("collocation", collocation), ("shooting", shooting)):
        x, z, t = solve(alpha)
        print(f"alpha {alpha}: {name:11s} x/L = {x:.8f}  y/L = {z:.8f}  theta = {t:.8f}")
