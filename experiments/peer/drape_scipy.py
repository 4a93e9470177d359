#!/usr/bin/python3
"""Independent implementation of the paper-1 drape (docs/scenes.md, docs/equilibrium.md) integrated by scipy BDF.

Written from paper 1's model only (no knitsim code): a square fabric of side W = 0.50 m and areal
density rho_A (g/m^2) becomes an (n+1) x (n+1) grid, n = max(2, floor(W/L0 + 0.5)), spacing
exactly L0, particle (i, j) at (j L0, i L0, 0), index i (n+1) + j. Masses rho_A (n L0)^2
lumped by area (interior 1, edge 1/2, corner 1/4). Springs with one stiffness k: structural
(rest L0), shear (both diagonals, rest sqrt(2) L0), bending (i,j)-(i,j+2), (i,j)-(i+2,j)
(rest 2 L0); topology a = all three. Pins: four_corner = the 4 corners, two_corner = (0,0) and
(0,n). State y = [x_free (3n); v_free (3n)],
    dx/dt = v,   dv/dt = M^-1 (F_spring(x) + m g - c v),
F_spring from springs (a, b): F_a = k (L - L0) u_ab, F_b = -F_a, u_ab = (x_b - x_a)/L.
Jacobian J = [[0, I], [M^-1 K, -c M^-1]], K per spring k [(1 - L0/L)(I - u u^T) + u u^T].
Equilibrium (docs/equilibrium.md): static residual r = max_i |F_i + m_i g| / (mean free mass g)
<= equilibrium_tol, checked at every BDF step (a terminal event on log r - log tol).
The elongation limit (Provot) is not modelled: with these parameters strains stay << 5 %
(the script prints the largest strain).
Potential energy (the equilibrium is a minimum of it, pins fixed):
    E(x) = sum_s k/2 (L_s - L0_s)^2 + sum_i m_i g z_i,   grad E = -(F_spring + m g),
    Hessian H = -K (sparse, the same blocks as the Jacobian's K).

As a module: Drape(...) gives rhs, jacobian, residual, energy, gradient, hessian;
run_bdf integrates to equilibrium; run_trust minimises E by a scipy.optimize trust-region
Newton method from the flat state; check_derivatives compares gradient and Hessian with
finite differences.
As a script:  drape_scipy.py --scene four_corner|two_corner [--out DIR] [--rtol R] ...
prints one JSON line (status, t_final, steps, cpu_seconds, residual) and, with --out, writes
nodes.csv (id,i,j,x,y,z,pinned) in knitsim's layout.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
from scipy.integrate import solve_ivp

G = 9.81  # m/s^2, along -z


class Drape:
    def __init__(self, layout="four_corner", width=0.50, areal_density=41.65, stiffness=852.0,
                 damping=12.0, natural_length=0.049, topology="a"):
        n = max(2, int(math.floor(width / natural_length + 0.5)))
        side = n + 1
        self.n, self.L0, self.k, self.c = n, natural_length, stiffness, damping
        ii, jj = np.meshgrid(np.arange(side), np.arange(side), indexing="ij")
        ii, jj = ii.ravel(), jj.ravel()
        self.ij = np.stack([ii, jj], axis=1)
        self.X0 = np.stack([jj * natural_length, ii * natural_length, 0.0 * ii], axis=1)
        w = np.where((ii == 0) | (ii == n), 0.5, 1.0) * np.where((jj == 0) | (jj == n), 0.5, 1.0)
        total = areal_density * 1e-3 * (n * natural_length) ** 2
        self.mass = w * total / w.sum()
        idx = lambda i, j: i * side + j
        a, b, rest = [], [], []

        def add(i0, j0, i1, j1, r):
            if max(i0, j0, i1, j1) <= n:
                a.append(idx(i0, j0)); b.append(idx(i1, j1)); rest.append(r)

        for i in range(side):
            for j in range(side):
                add(i, j, i, j + 1, natural_length)
                add(i, j, i + 1, j, natural_length)
                if topology in "ab":
                    add(i, j, i + 1, j + 1, math.sqrt(2) * natural_length)
                    add(i, j + 1, i + 1, j, math.sqrt(2) * natural_length)
                if topology in "ac":
                    add(i, j, i, j + 2, 2 * natural_length)
                    add(i, j, i + 2, j, 2 * natural_length)
        self.a, self.b, self.rest = np.array(a), np.array(b), np.array(rest)
        pins = [idx(0, 0), idx(0, n)]
        if layout == "four_corner":
            pins += [idx(n, 0), idx(n, n)]
        self.pinned = np.zeros(side * side, bool)
        self.pinned[pins] = True
        self.free = np.flatnonzero(~self.pinned)
        self.nf = len(self.free)
        self.free_index = -np.ones(side * side, int)
        self.free_index[self.free] = np.arange(self.nf)
        S = len(self.a)
        # Incidence D (springs x particles): d_s = x_b - x_a = (D X)_s.
        self.D = sp.csr_matrix((np.r_[-np.ones(S), np.ones(S)], (np.r_[np.arange(S), np.arange(S)],
                                np.r_[self.a, self.b])), shape=(S, side * side))
        self.mfree = self.mass[self.free]
        self.inv_m3 = np.repeat(1.0 / self.mfree, 3)
        self.F_ref = self.mfree.mean() * G
        self._jac_pattern()

    # --- state <-> all positions
    def positions(self, xf):
        X = self.X0.copy()
        X[self.free] = xf.reshape(-1, 3)
        return X

    def y0(self):
        return np.r_[self.X0[self.free].ravel(), np.zeros(3 * self.nf)]

    def spring_force(self, X):
        """Net spring force on every particle (P x 3) and the spring lengths."""
        d = self.D @ X
        L = np.sqrt((d * d).sum(1))
        f = (self.k * (L - self.rest) / L)[:, None] * d
        return -(self.D.T @ f), d, L

    def rhs(self, t, y):
        N = 3 * self.nf
        F, _, _ = self.spring_force(self.positions(y[:N]))
        acc = F[self.free].ravel() * self.inv_m3 - self.c * self.inv_m3 * y[N:]
        acc[2::3] -= G
        return np.r_[y[N:], acc]

    def residual(self, xf):
        F, _, _ = self.spring_force(self.positions(xf))
        F = F[self.free]
        F[:, 2] -= self.mfree * G
        return np.sqrt((F * F).sum(1)).max() / self.F_ref

    def max_strain(self, xf):
        _, _, L = self.spring_force(self.positions(xf))
        return float(((L - self.rest) / self.rest).max())

    def _jac_pattern(self):
        """COO index arrays of the 4 blocks (aa, ab, ba, bb) of every spring, free ends only."""
        fa, fb = self.free_index[self.a], self.free_index[self.b]
        rows, cols, sign, spring = [], [], [], []
        r3, c3 = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
        for p, q, s in ((fa, fa, -1.0), (fa, fb, 1.0), (fb, fa, 1.0), (fb, fb, -1.0)):
            ok = (p >= 0) & (q >= 0)
            sel = np.flatnonzero(ok)
            rows.append((3 * p[sel][:, None] + r3.ravel()).ravel())
            cols.append((3 * q[sel][:, None] + c3.ravel()).ravel())
            sign.append(np.full(9 * len(sel), s))
            spring.append(np.repeat(sel, 9))
        self.jr, self.jc = np.concatenate(rows), np.concatenate(cols)
        self.js, self.jspring = np.concatenate(sign), np.concatenate(spring)

    def stiffness(self, xf):
        """K = dF_spring/dx over free dof (3n x 3n, CSR)."""
        _, d, L = self.spring_force(self.positions(xf))
        u = d / L[:, None]
        uu = u[:, :, None] * u[:, None, :]
        blk = self.k * ((1 - self.rest / L)[:, None, None] * (np.eye(3) - uu) + uu)
        vals = self.js * blk.reshape(-1, 9)[self.jspring, np.tile(np.arange(9), len(self.jspring) // 9)]
        N = 3 * self.nf
        return sp.csr_matrix((vals, (self.jr, self.jc)), shape=(N, N))

    def energy_long(self, xf):
        """Potential energy E (J) of the free positions xf (3 nf), springs + gravity, summed in
        extended precision (numpy longdouble: a 64-bit mantissa on x86). run_trust subtracts E
        at its restart point before rounding to a double (below)."""
        X = self.positions(xf).astype(np.longdouble)
        d = X[self.b] - X[self.a]
        L = np.sqrt((d * d).sum(1))
        return 0.5 * self.k * ((L - self.rest) ** 2).sum() + G * (self.mass * X[:, 2]).sum()

    def energy(self, xf):
        """Potential energy E (J), as a double."""
        return float(self.energy_long(xf))

    def gradient(self, xf):
        """dE/dx over free dof (3 nf): minus the net static force."""
        F, _, _ = self.spring_force(self.positions(xf))
        F = F[self.free]
        F[:, 2] -= self.mfree * G
        return -F.ravel()

    def hessian(self, xf):
        """d2E/dx2 = -K over free dof (3 nf x 3 nf, CSR)."""
        return -self.stiffness(xf)

    def jacobian(self, t, y):
        N = 3 * self.nf
        K = self.stiffness(y[:N])
        Minv = sp.diags(self.inv_m3)
        return sp.bmat([[None, sp.identity(N)], [Minv @ K, -self.c * Minv]], format="csc")


def run_bdf(model, rtol=1e-6, atol=1e-9, equilibrium_tol=1e-8, t_max=1e7):
    """scipy BDF from the flat state at rest to equilibrium (terminal residual event)."""
    N = 3 * model.nf

    def settled(t, y):
        return math.log(model.residual(y[:N]) + 1e-300) - math.log(equilibrium_tol)
    settled.terminal, settled.direction = True, -1
    cpu0, wall0 = time.process_time(), time.perf_counter()
    sol = solve_ivp(model.rhs, (0.0, t_max), model.y0(), method="BDF", jac=model.jacobian,
                    rtol=rtol, atol=atol, events=settled)
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    y = sol.y_events[0][0] if sol.status == 1 else sol.y[:, -1]
    t = sol.t_events[0][0] if sol.status == 1 else sol.t[-1]
    status = {1: "equilibrium", 0: "time_limit"}.get(sol.status, "solver_failure")
    return dict(status=status, t_final=float(t), steps=int(len(sol.t) - 1), rhs_evals=int(sol.nfev),
                jac_evals=int(sol.njev), lu=int(sol.nlu), residual=float(model.residual(y[:N])),
                max_strain=model.max_strain(y[:N]), cpu_seconds=cpu, wall_seconds=wall), y


TRUST_METHODS = ("trust-krylov", "trust-ncg", "trust-exact")


class _Stopped(Exception):
    """Raised by run_trust's callback to end scipy's minimize (scipy 1.10 has no other way)."""


def run_trust(model, method="trust-exact", position_tol=1e-10, test_below=1e-4, maxiter=3000,
              rounds=8):
    """Minimise E from the flat start by scipy.optimize.minimize(method): a trust-region Newton
    method with the analytic gradient and the sparse analytic Hessian (dense for trust-exact,
    which factorises it; as a Hessian-vector product for trust-krylov and trust-ncg).

    Stop: knitsim's stop in positions (docs/equilibrium.md): the Newton correction
    ||H^-1 grad E||_inf (sparse LU of H) <= position_tol, m, tested in minimize's callback at
    every iterate whose static residual is below `test_below` and has fallen tenfold since the
    last test, and where a round ends. scipy's own stop (gtol) is 0: only this test ends a run.
    Near the minimum a Newton step changes E by ~ |grad E|^2 / lambda_min, below a double's
    round-off of E (~1e-18 J here) before the stop holds, and scipy's ratio test then rejects
    every step ("A bad approximation caused failure to predict improvement"). So the objective
    is E(x) - E(x_r), summed in extended precision (energy_long) and rounded to a double after
    the subtraction, and minimize restarts from its last iterate x_r with E(x_r) as the new
    shift, up to `rounds` times of at most `maxiter` iterations each (knitsim's solver instead
    accepts a step on a falling |F| there); a restart that takes no step ends the run as
    "stalled", its Newton correction reported. The counters add up over the rounds (hess_evals:
    dense Hessians for trust-exact, Hessian-vector products otherwise); the certificate (H's
    smallest eigenvalue) is computed after the timed solve."""
    from scipy.optimize import minimize
    from scipy.sparse.linalg import splu
    x = model.X0[model.free].ravel()
    cache = {}

    def hess(z):  # one assembly per iterate, shared by the products at that iterate
        key = z.tobytes()
        if cache.get("key") != key:
            cache["key"], cache["H"] = key, model.hessian(z)
        return cache["H"]

    state = dict(tested_at=math.inf, tests=0, newton_step=math.inf, x=x)
    counts = dict(iterations=0, fun_evals=0, grad_evals=0, hess_evals=0)

    def counted(key, f):
        def g(*a):
            counts[key] += 1
            return f(*a)
        return g

    def stop_test(z):
        state["tested_at"], state["tests"] = model.residual(z), state["tests"] + 1
        dx = splu(hess(z).tocsc()).solve(model.gradient(z))
        state["newton_step"] = float(np.abs(dx).max())
        return state["newton_step"] <= position_tol

    def callback(z):
        state["x"] = z
        counts["iterations"] += 1
        r = model.residual(z)
        if r <= test_below and r <= 0.1 * state["tested_at"] and stop_test(z):
            raise _Stopped()

    kw = dict(jac=counted("grad_evals", model.gradient), callback=callback,
              options=dict(gtol=0.0, maxiter=maxiter))
    if method == "trust-exact":
        kw["hess"] = counted("hess_evals", lambda z: hess(z).toarray())
    else:
        kw["hessp"] = counted("hess_evals", lambda z, p: hess(z) @ p)
    messages, stopped = [], False
    cpu0, wall0 = time.process_time(), time.perf_counter()
    for r in range(1, rounds + 1):
        shift = model.energy_long(x)
        try:
            res = minimize(counted("fun_evals", lambda z: float(model.energy_long(z) - shift)),
                           x, method=method, **kw)
            moved = not np.array_equal(res.x, x)
            x = res.x
            messages.append(str(res.message))
            if model.residual(x) <= test_below and stop_test(x):  # where scipy gave up
                stopped = True
                break
            if not moved:  # a restart that cannot take a single step: scipy is stuck here
                break
        except _Stopped:
            x, stopped = state["x"], True
            messages.append("stop in positions")
            break
    cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
    lam_min = float(np.linalg.eigvalsh(model.hessian(x).toarray()).min())
    # stalled: scipy ended (no step accepted after a restart) short of the stop in positions.
    status = ("equilibrium" if stopped else "stalled") if lam_min > 0 else "failure"
    return dict(method=method, status=status, message=" | ".join(messages), rounds=r,
                stop_tests=state["tests"], newton_step=state["newton_step"],
                energy=model.energy(x), residual=float(model.residual(x)),
                min_eigenvalue=lam_min, max_strain=model.max_strain(x), cpu_seconds=cpu,
                wall_seconds=wall, **counts), x


def check_derivatives(model, seed=3, h=1e-7):
    """Largest relative differences of gradient (vs central differences of E) and Hessian (vs
    central differences of the gradient, along random directions) at a random state near the
    flat start: (gradient error, Hessian error)."""
    rng = np.random.default_rng(seed)
    x = model.X0[model.free].ravel() + 1e-3 * rng.standard_normal(3 * model.nf)
    g, H = model.gradient(x), model.hessian(x)
    g_err, h_err = 0.0, 0.0
    for _ in range(5):
        p = rng.standard_normal(x.size)
        p /= np.linalg.norm(p)
        fd = (model.energy(x + h * p) - model.energy(x - h * p)) / (2 * h)
        g_err = max(g_err, abs(fd - g @ p) / max(abs(g @ p), 1e-300))
        fd_h = (model.gradient(x + h * p) - model.gradient(x - h * p)) / (2 * h)
        h_err = max(h_err, np.linalg.norm(fd_h - H @ p) / np.linalg.norm(H @ p))
    return g_err, h_err


def write_nodes(path, model, y):
    X = model.positions(y[:3 * model.nf])
    with open(path, "w") as f:
        f.write("id,i,j,x,y,z,pinned\n")
        for p in range(len(X)):
            f.write("%d,%d,%d,%.17g,%.17g,%.17g,%d\n" % (p, model.ij[p, 0], model.ij[p, 1],
                    X[p, 0], X[p, 1], X[p, 2], int(model.pinned[p])))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default="four_corner", choices=["four_corner", "two_corner"])
    ap.add_argument("--rtol", type=float, default=1e-6)
    ap.add_argument("--atol", type=float, default=1e-9)
    ap.add_argument("--equilibrium-tol", type=float, default=1e-8)
    ap.add_argument("--out", default="")
    ap.add_argument("--position-tol", type=float, default=1e-10,
                    help="trust-*: the stop in positions, m")
    ap.add_argument("--method", default="bdf", choices=("bdf",) + TRUST_METHODS,
                    help="bdf: solve_ivp BDF to equilibrium; trust-*: minimise the energy")
    a = ap.parse_args()
    model = Drape(layout=a.scene)
    if a.method == "bdf":
        stats, y = run_bdf(model, a.rtol, a.atol, a.equilibrium_tol)
    else:
        stats, y = run_trust(model, a.method, a.position_tol)
    stats["scene"] = a.scene
    if a.out:
        os.makedirs(a.out, exist_ok=True)
        write_nodes(os.path.join(a.out, "nodes.csv"), model, y)
        json.dump(stats, open(os.path.join(a.out, "summary.json"), "w"), indent=2)
    print(json.dumps(stats))
    return 0 if stats["status"] == "equilibrium" else 3


if __name__ == "__main__":
    sys.exit(main())
