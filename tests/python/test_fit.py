"""knitsim.fit is `knitsim fit` (the ICA): the same best country, objective, history and fitted
drape, bit for bit; its bad input raises ValueError with the command's message."""
import csv
import json
import os

import numpy as np
import pytest

import knitsim
from conftest import ROOT, run_cli

TARGET = os.path.join(ROOT, "docs", "examples", "lab_targets.csv")
SCENE = os.path.join(ROOT, "docs", "examples", "my_fabric.toml")
BUDGET = dict(decades=2, countries=6, imperialists=2, seed=3)


def test_same_fit_as_the_cli(cli, tmp_path):
    flags = [a for k, v in BUDGET.items() for a in ("--" + k, str(v))]
    status, _, err = run_cli(cli, "fit", "--scene", SCENE, "--target", TARGET, "--out",
                             str(tmp_path), "--quiet", "--no-pictures", *flags)
    assert status == 0, err
    s = json.loads((tmp_path / "summary.json").read_text())
    r = knitsim.fit(TARGET, SCENE, **BUDGET)
    assert r.status == s["status"] == "decade_limit"
    assert r.params == s["params"] and r.objective == s["objective"]
    assert r.best_country.tolist() == s["best_country"]
    assert r.evaluations == s["evaluations"] and r.failed_evaluations == s["failed_evaluations"]
    assert r.history == s["history"]
    # The fitted drape, re-run: drape/ of the command.
    with open(tmp_path / "drape" / "nodes.csv") as f:
        rows = list(csv.DictReader(f))
    xyz = np.array([[float(x["x"]), float(x["y"]), float(x["z"])] for x in rows])
    assert np.array_equal(r.drape.positions[[int(x["id"]) for x in rows]], xyz)
    d = json.loads((tmp_path / "drape" / "summary.json").read_text())
    assert r.drape.summary["objective"] == d["objective"] == r.objective

    # summary is the command's summary.json (its units map included), the wall time aside.
    assert "units" in r.summary and r.summary["units"] == s["units"]
    assert without_timings(r.summary) == without_timings(s)
    assert r.summary["wall_seconds"] == r.wall_seconds

    # result.write() writes the command's files: the same bytes, timings and manifests aside.
    py_dir = tmp_path / "py"
    assert r.write(py_dir, pictures=False) == str(py_dir)
    assert sorted(os.listdir(py_dir)) == sorted(set(os.listdir(tmp_path)) - {"py",
                                                "ica_checkpoint.json"})
    assert sorted(os.listdir(py_dir / "drape")) == sorted(os.listdir(tmp_path / "drape"))
    for name in ["history.csv", "drape/nodes.csv", "drape/edges.csv", "drape/target_edges.csv",
                 "drape/drape.vtk", "drape/state.json"]:
        assert (py_dir / name).read_bytes() == (tmp_path / name).read_bytes(), name
    for name in ["summary.json", "drape/summary.json"]:
        assert without_timings(json.loads((py_dir / name).read_text())) == \
            without_timings(json.loads((tmp_path / name).read_text())), name
    for name in ["manifest.json", "drape/manifest.json"]:
        m_py, m_cli = (json.loads((d / name).read_text()) for d in (py_dir, tmp_path))
        assert m_py["options"] == m_cli["options"], name


def without_timings(summary):
    return {k: v for k, v in summary.items() if k not in ("wall_seconds", "cpu_seconds")}


def test_bounds_narrow_the_search():
    r = knitsim.fit(TARGET, SCENE, bounds={"stiffness": (600, 610), "topology": (0, 1)}, **BUDGET)
    assert 600 <= r.params["stiffness"] <= 610 and r.params["topology"] == "a"


@pytest.mark.parametrize("kwargs,flags", [
    (dict(countries=1), ["--countries", "1"]),
    (dict(decades=0), ["--decades", "0"]),
    (dict(integrator="foo"), ["--integrator", "foo"]),
    (dict(rtol=0), ["--rtol", "0"]),
])
def test_bad_fit_input_has_the_cli_message(cli, tmp_path, kwargs, flags):
    with pytest.raises(ValueError) as e:
        knitsim.fit(TARGET, SCENE, **kwargs)
    status, _, err = run_cli(cli, "fit", "--scene", SCENE, "--target", TARGET, "--out",
                             str(tmp_path / "o"), "--quiet", *flags)
    assert status == 2
    assert str(e.value) == err.strip().splitlines()[-1][len("knitsim: error: "):]


@pytest.mark.parametrize("kwargs,fragment", [
    (dict(target="/nonexistent.csv"), "/nonexistent.csv"),
    (dict(bounds={"stiffnes": (1, 2)}), "bounds: stiffnes: unknown key; did you mean stiffness?"),
    (dict(bounds={"stiffness": 5}), "bounds.stiffness: expected (lower, upper), got 5"),
    (dict(bounds={"stiffness": (900, 800)}), "bounds.stiffness = [900, 800]"),
    (dict(bounds=[1]), "bounds: expected a dict"),
    (dict(seed=-1), "--seed = -1: must be a decimal integer >= 0"),
    (dict(stop_one_empire=1), "--stop-one-empire = 1: must be True or False"),
    (dict(countrys=5), "countrys: unknown key; did you mean countries?"),
])
def test_bad_fit_values(kwargs, fragment):
    args = dict(target=TARGET, scene=SCENE)
    args.update(kwargs)
    with pytest.raises(ValueError) as e:
        knitsim.fit(**args)
    assert fragment in str(e.value)
