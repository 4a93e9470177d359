"""The module is the one built for this interpreter, and what it lists is the CLI's."""
import os
import sys

import knitsim
from conftest import run_cli


def test_built_for_this_interpreter():
    # A module built for another interpreter (another Python, or another install of the same
    # version) must fail this, not run against headers it was not built for.
    built = knitsim.build["python"]
    assert os.path.realpath(built) == os.path.realpath(sys.executable), (built, sys.executable)
    assert knitsim.build["python_version"] == f"{sys.version_info[0]}.{sys.version_info[1]}"
    assert knitsim.__file__.endswith(".so")


def test_version_is_the_cli_version(cli):
    status, out, _ = run_cli(cli, "--version")
    assert status == 0
    assert out.strip() == knitsim.build["version"]
    assert knitsim.build["version"].startswith("knitsim " + knitsim.__version__ + " ")


def test_list_keys_is_the_cli_table(cli):
    status, out, _ = run_cli(cli, "list", "keys", "--format", "csv")
    assert status == 0
    import csv, io
    rows = list(csv.DictReader(io.StringIO(out)))
    assert rows == knitsim.list_keys()
    keys = [k["key"] for k in knitsim.list_keys()]
    assert "model.stiffness" in keys and "run.position_tol" in keys


def test_integrators_are_the_registry(cli):
    status, out, _ = run_cli(cli, "list", "integrators", "--format", "csv")
    assert status == 0
    names = [line.split(",")[0] for line in out.splitlines()[1:]]
    assert names == [i["name"] for i in knitsim.integrators()]
    assert "equilibrium" in names


def test_help_lists_every_key_with_unit_default_and_range():
    doc = knitsim.drape.__doc__
    for k in knitsim.list_keys():
        where = doc
        if k["model"] == "fit":  # a fitting command's flag: in fit()'s help if it is its keyword
            if k["key"].startswith("--lm-") or k["key"] in ("--noise-mm", "--photos"):
                continue  # knitsim.fit runs the ICA; the targets are the CLI's
            where = knitsim.fit.__doc__
        line = next(l for l in where.splitlines() if l.strip().startswith(k["key"] + " ("))
        assert k["unit"] in line and "default " + k["default"] in line and k["accepted"] in line
    assert "model.stiffness (N/m; default 852; > 0 N/m" in doc.replace("\n", " ") or \
        "model.stiffness (N/m; default 852;" in doc


def test_import_starts_no_mpi():
    # Importing maps neither libmpi nor the MPI module.
    with open("/proc/self/maps") as f:
        maps = f.read()
    assert "libmpi" not in maps and "libknitsim_mpi" not in maps
