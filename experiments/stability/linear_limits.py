#!/usr/bin/python3
"""Exact linear stability limits of euler, verlet and arkode-erk on a drape (solvers/integrator.hpp, predict_stable_dt).

The drape ODE linearised at the flat start (experiments/peer/drape_scipy.py builds the model
independently of knitsim), y' = J y + const, J = [[0, I], [-A, -Gamma]] with A = -M^-1 K and
Gamma = diag(c/m_i). With the eigenvalues lambda of J (dense, all of them):
  euler:      |1 + h lambda| <= 1 for all lambda  <=>  h <= 2 |Re lambda| / |lambda|^2;
  arkode-erk: |R(h lambda)| <= 1 for all lambda, R(z) = 1 + z b^T (I - z A_rk)^-1 1 the
              stability function of ARKODE's default order-4 table (ARKODE_ZONNEVELD_5_3_4,
              loaded from libsundials_arkode so it is the table the solver uses);
  verlet:     spectral radius of the one-step matrix S(h) of knitsim's velocity Verlet with
              exact damping half-steps (solvers/explicit.cpp): e = exp(-gamma h/2),
              phi = (1 - e)/gamma:  v+ = E v + Phi A x,  x' = x + h v+,  v' = E v+ + Phi A x'.
These are the exact counterparts of predict_stable_dt's per-dof Gershgorin bound
(omega_i^2 <= sum_j |A_ij|), which ignores the coupling between dof and can only be
conservative. The largest h is found by scanning up from 0 and bisecting (relative 1e-3).
"""
import ctypes
import math

import numpy as np


def erk_table(name=b"ARKODE_ZONNEVELD_5_3_4"):
    class Table(ctypes.Structure):
        _fields_ = [("q", ctypes.c_int), ("p", ctypes.c_int), ("stages", ctypes.c_int),
                    ("A", ctypes.POINTER(ctypes.POINTER(ctypes.c_double))),
                    ("c", ctypes.POINTER(ctypes.c_double)), ("b", ctypes.POINTER(ctypes.c_double)),
                    ("d", ctypes.POINTER(ctypes.c_double))]
    lib = ctypes.CDLL("libsundials_arkode.so.5")
    lib.ARKodeButcherTable_LoadERKByName.restype = ctypes.POINTER(Table)
    lib.ARKodeButcherTable_LoadERKByName.argtypes = [ctypes.c_char_p]
    t = lib.ARKodeButcherTable_LoadERKByName(name).contents
    s = t.stages
    A = np.array([[t.A[i][j] for j in range(s)] for i in range(s)])
    b = np.array([t.b[i] for i in range(s)])
    return A, b


def erk_polynomial(A, b):
    """Coefficients of R(z) = sum_j z^j b^T A^(j-1) 1 (explicit table: a polynomial)."""
    s = len(b)
    coef, v = [1.0], np.ones(s)
    for _ in range(s):
        coef.append(float(b @ v))
        v = A @ v
    return np.array(coef)


def largest_stable(is_stable, h0):
    """Largest h with is_stable(h), scanning from h0 by factors 1.25, then bisecting to 1e-3."""
    lo = h0
    while not is_stable(lo):
        lo /= 1.25
        if lo < 1e-6 * h0:
            return 0.0
    hi = lo * 1.25
    while is_stable(hi):
        lo, hi = hi, hi * 1.25
        if hi > 1e6 * h0:
            return math.inf
    while hi - lo > 1e-3 * lo:
        mid = 0.5 * (lo + hi)
        if is_stable(mid):
            lo = mid
        else:
            hi = mid
    return lo


def limits(model, verlet_guess):
    """Exact linear limits (s) of euler, verlet, arkode-erk at the flat start of `model`;
    verlet_guess (s, e.g. predict_stable_dt) starts the scan of the costly Verlet check."""
    N = 3 * model.nf
    y0 = model.y0()
    J = model.jacobian(0.0, y0).toarray()
    lam = np.linalg.eigvals(J)
    scale = np.abs(lam).max()
    # The system is passive (c >= 0): a positive real part is eigen-solver round-off (~1e-11
    # |lambda|), which would otherwise make every undamped mode look unstable for any h.
    lam = np.minimum(lam.real, 0.0) + 1j * lam.imag
    # Zero modes (flat sheet: no z stiffness) never limit; defective ones come out of the
    # eigen-solver split by ~sqrt(eps) |lambda|max, hence the 1e-8 relative threshold.
    lam = lam[np.abs(lam) > 1e-8 * scale]
    out = {}
    re = np.maximum(-lam.real, 0.0)
    out["euler"] = float((2.0 * re / np.abs(lam) ** 2).min())
    coef = erk_polynomial(*erk_table())
    R = lambda z: np.polyval(coef[::-1], z)
    h_guess = 0.1 / scale
    out["arkode-erk"] = largest_stable(lambda h: np.abs(R(h * lam)).max() <= 1.0 + 1e-12, h_guess)
    A = model.stiffness(y0[:N]).toarray() * model.inv_m3[:, None]
    gamma = model.c * model.inv_m3
    I = np.eye(N)

    def verlet_stable(h):
        e = np.exp(-0.5 * gamma * h)
        phi = np.where(gamma > 0, -np.expm1(-0.5 * gamma * h) / np.where(gamma > 0, gamma, 1), 0.5 * h)
        # (x, v) -> v+ = e v + phi A x ; x' = x + h v+ ; v' = e v+ + phi A x'
        Vp = np.hstack([phi[:, None] * A, np.diag(e)])
        Xn = np.hstack([I, np.zeros((N, N))]) + h * Vp
        Vn = e[:, None] * Vp + (phi[:, None] * A) @ Xn
        S = np.vstack([Xn, Vn])
        return np.abs(np.linalg.eigvals(S)).max() <= 1.0 + 1e-7
    out["verlet"] = largest_stable(verlet_stable, verlet_guess)
    out["omega_max"] = float(np.abs(lam.imag).max())
    out["lambda_abs_max"] = float(scale)
    return out
