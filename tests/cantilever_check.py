#!/usr/bin/python3
"""ctest cantilever_scene: `knitsim drape --scene cantilever` against the heavy elastica.

The reference, solved here independently of the model (docs/material_drape.md, "Peirce's
cantilever"): B theta'' = -w (L - s) cos theta, theta(0) = 0, theta'(L) = 0; in s / L it depends
on G = w L^3 / B alone, theta'' = -G (1 - s) cos theta; theta'(0) by bracketing and brentq on
shots integrated by DOP853 (rtol 1e-12), carrying the tip's run int cos theta and drop
int sin theta.

For overhangs from small deflection (G = 0.1, drop ~ w L^4 / 8B) through Peirce's point (G = 8,
L = 2c, chord 41.49 deg) to beyond it (G = 20), the scene is run with 16 and 32 cells on the
overhang (mesh.cells = cells across the 25 mm strip, set for that); the chord angle and the tip
drop of the finer mesh must be within 1 % of the elastica's, the coarser within 2 %. Then the
check must be able to fail: the same scene with the bending rigidity 5 % off at G = 8, compared
with the elastica of the scene's own B, must be more than 1 % off in the chord. And cvode-bdf must
settle the default scene within 2000 steps at the equilibrium solver's chord (to 1e-6).

Usage: cantilever_check.py KNITSIM [--quick]  (--quick: G = 8 only)
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


def elastica(G):
    """Tip run / L, drop / L and slope (rad) of the heavy elastica at G = w L^3 / B."""
    def shot(k0):
        f = lambda s, y: [y[1], -G * (1.0 - s) * math.cos(y[0]), math.cos(y[0]), math.sin(y[0])]
        r = solve_ivp(f, [0.0, 1.0], [0.0, k0, 0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14)
        return r.y[:, -1]
    k = brentq(lambda k0: shot(k0)[1], 0.0, G, xtol=1e-15)  # theta'(0) in (0, G/2 ...]
    theta, _, x, z = shot(k)
    return x, z, theta


def run(knitsim, out, sets):
    cmd = [knitsim, "drape", "--scene", "cantilever", "--no-pictures", "--quiet", "--out", out]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def main():
    knitsim = sys.argv[1]
    quick = "--quick" in sys.argv
    base = tempfile.mkdtemp(prefix="cantilever_check_")
    scene = run(knitsim, os.path.join(base, "default"), [])
    p = scene["params"]
    w = p["areal_density_g_m2"] * 1e-3 * 9.81
    B = p["bending_wale_Nm"]
    width = p["width_m"]
    c = (B / w) ** (1.0 / 3.0)
    failures = []
    # Every run option that is a number has its unit in summary.json, from the key table's rows.
    named = {name for group in scene["units"]["options"].split("; ")
             for name in group.rsplit(" ", 1)[0].split(", ")}
    for name, value in scene["options"].items():
        if isinstance(value, (int, float)) and not isinstance(value, bool) and name not in named:
            failures.append(f"units.options names no unit for {name}")
    print(f"bending length c = {1e3 * c:.4f} mm (B_w = {B} N m, w = {w:.4f} N/m^2)")
    print("G        L (mm)   ny     chord (deg)  elastica   err %    drop/L     elastica  err %")
    for G in ([8.0] if quick else [0.1, 8.0, 20.0]):
        L = (G * B / w) ** (1.0 / 3.0)
        x, z, theta = elastica(G)
        chord_ref = math.degrees(math.atan2(z, x))
        for n_over, tol in ((16, 2.0), (32, 1.0)):
            cells = max(2, round(n_over * width / L))
            s = run(knitsim, os.path.join(base, f"G{G}_{n_over}"),
                    [f"clamps.overhang={L!r}", f"mesh.cells={cells}"])
            assert s["status"] == "equilibrium", s["status"]
            assert s["params"]["overhang_m"] == L
            chord_err = 100 * (s["chord_angle_deg"] / chord_ref - 1)
            drop_err = 100 * (s["tip_drop_m"] / L / z - 1)
            print(f"{G:<8g} {1e3 * L:<8.3f} {s['mesh']['cells_y']:<6d} {s['chord_angle_deg']:<12.5f} "
                  f"{chord_ref:<10.5f} {chord_err:<+8.4f} {s['tip_drop_m'] / L:<10.6f} {z:<9.6f} "
                  f"{drop_err:+.4f}")
            if abs(chord_err) > tol or abs(drop_err) > tol:
                failures.append(f"G = {G}, {n_over} cells: chord {chord_err:+.3f} %, "
                                f"drop {drop_err:+.3f} % (tolerance {tol} %)")
    # The dynamic integrators settle it too (material.damping, docs/material_drape.md,
    # "Damping"): cvode-bdf within 2000 steps, at the equilibrium solver's chord.
    for integrator in ("cvode-bdf",):
        out = os.path.join(base, integrator)
        subprocess.run([knitsim, "drape", "--scene", "cantilever", "--no-pictures", "--quiet",
                        "--integrator", integrator, "--max-steps", "2000", "--out", out],
                       check=False)
        with open(os.path.join(out, "summary.json")) as f:
            d = json.load(f)
        agree = d["status"] == "equilibrium" and \
            abs(d["chord_angle_deg"] / scene["chord_angle_deg"] - 1) < 1e-6
        print(f"{integrator}: {d['status']} in {d['steps']} steps, chord {d['chord_angle_deg']:.6f} "
              f"deg (equilibrium solver {scene['chord_angle_deg']:.6f})")
        if not agree:
            failures.append(f"{integrator} does not settle the cantilever at the equilibrium "
                            "solver's chord within 2000 steps")
    # The check can fail: the bending rigidity 5 % off at G = 8.
    L = 2.0 * c
    x, z, theta = elastica(8.0)
    chord_ref = math.degrees(math.atan2(z, x))
    cells = max(2, round(32 * width / L))
    s = run(knitsim, os.path.join(base, "wrong_bending"),
            [f"clamps.overhang={L!r}", f"mesh.cells={cells}", f"material.bending_wale={1.05 * B!r}"])
    wrong = 100 * (s["chord_angle_deg"] / chord_ref - 1)
    print(f"B_w 5 % too high at G = 8: chord {s['chord_angle_deg']:.4f} deg, {wrong:+.3f} % "
          f"against the elastica (must be outside 1 %)")
    if abs(wrong) <= 1.0:
        failures.append("a 5 % error in the bending rigidity passes the 1 % check")
    if failures:
        print("FAIL:\n  " + "\n  ".join(failures))
        return 1
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
