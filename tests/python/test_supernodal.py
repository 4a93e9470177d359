"""A drape past SymmetricFactor::supernodal_min_dof (33 000 unknowns) runs CHOLMOD's supernodal
factorisation, whose BLAS knitsim loads on first use, in a process where numpy has loaded its
own BLAS -- in both import orders -- and gives the CLI's numbers."""
import csv
import json
import os

import numpy as np
import pytest

from conftest import run_cli, run_python

# 106 x 106 particles, 33 708 unknowns with no mirror reduction; two steps of the equilibrium
# solver (each factorises S) keep it to seconds. The run ends at its step cap, which is a status.
OVERRIDES = {"model.natural_length": 0.00472, "model.symmetry": "none"}
FLAGS = [a for k, v in OVERRIDES.items() for a in ("--set", f"{k}={v}")] + ["--max-steps", "2"]

SCRIPT = """
import json, sys
{first}
{second}
r = knitsim.drape("four_corner", {overrides!r}, max_steps=2)
np.save(sys.argv[1] if len(sys.argv) > 1 else {out!r}, r.positions)
s = r.summary
print(json.dumps({{"status": r.status, "factorization": s["factorization"],
                   "dof": s["grid"]["integrated_dof"], "factorisations": s["factorisations"],
                   "blas_in_maps": "blas" in open("/proc/self/maps").read()}}))
"""


@pytest.fixture(scope="module")
def cli_positions(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("supernodal_cli")
    status, _, err = run_cli(cli, "drape", "--out", str(out), "--quiet", "--no-pictures", *FLAGS)
    assert status == 3, err  # step_limit
    with open(out / "nodes.csv") as f:
        rows = list(csv.DictReader(f))
    ids = np.array([int(r["id"]) for r in rows])
    xyz = np.empty((len(rows), 3))
    xyz[ids] = [[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows]
    return xyz


@pytest.mark.parametrize("first,second", [("import numpy as np", "import knitsim"),
                                          ("import knitsim", "import numpy as np")])
def test_supernodal_drape_beside_numpy(cli_positions, tmp_path, first, second):
    out = str(tmp_path / "positions.npy")
    p = run_python(SCRIPT.format(first=first, second=second, overrides=OVERRIDES, out=out))
    assert p.returncode == 0, p.stderr
    info = json.loads(p.stdout.strip().splitlines()[-1])
    assert info["status"] == "step_limit" and info["factorization"] == "supernodal", info
    assert info["dof"] >= 33000 and info["factorisations"] >= 1 and info["blas_in_maps"], info
    assert np.array_equal(np.load(out), cli_positions)
