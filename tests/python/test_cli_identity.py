"""knitsim.drape gives the CLI's numbers bit for bit, and result.write() its files byte for byte
(timings aside: summary.json's wall and CPU seconds, manifest.json's time and command line)."""
import csv
import json
import os

import numpy as np
import pytest

import knitsim
from conftest import run_cli

# Files whose every byte must match; summary.json and manifest.json are compared as JSON below.
SAME_BYTES = ["nodes.csv", "edges.csv", "drape.vtk", "state.json", "drape.png"]
TIMINGS = {"wall_seconds", "cpu_seconds"}


def nodes(folder):
    """nodes.csv as (ids, positions): %.17g reads back as the very doubles written."""
    with open(os.path.join(folder, "nodes.csv")) as f:
        rows = list(csv.DictReader(f))
    ids = np.array([int(r["id"]) for r in rows])
    xyz = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows])
    return ids, xyz


def without_timings(summary):
    return {k: v for k, v in summary.items() if k not in TIMINGS}


CASES = [
    ("four_corner", {}, None),
    ("two_corner", {}, None),
    ("two_corner_slack", {}, None),
    ("four_corner", {"model.stiffness": 900, "model.topology": "b"}, "cvode-bdf"),
]


@pytest.mark.parametrize("scene,overrides,integrator", CASES)
def test_same_numbers_and_files_as_the_cli(cli, tmp_path, scene, overrides, integrator):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    args = ["drape", "--scene", scene, "--out", str(cli_dir), "--quiet"]
    for k, v in overrides.items():
        args += ["--set", f"{k}={v}"]
    if integrator:
        args += ["--integrator", integrator]
    status, _, err = run_cli(cli, *args)
    assert status == 0, err

    r = knitsim.drape(scene, overrides, integrator)
    assert r.status == "equilibrium" and r.certificate
    assert r.write(py_dir) == str(py_dir)

    # The arrays are the CLI's doubles, bit for bit.
    ids, xyz = nodes(cli_dir)
    assert np.array_equal(r.positions[ids], xyz)
    assert r.positions.shape == (len(ids), 3) and r.rest_positions.shape == r.positions.shape
    assert np.array_equal(r.index.ravel(), ids)  # nodes.csv is in (i, j) order
    with open(cli_dir / "edges.csv") as f:
        rows = list(csv.DictReader(f))
    assert rows, "the CLI measured no edges"
    assert sorted(r.edges) == sorted({row["edge"] for row in rows})
    for name, edge in r.edges.items():
        points = [row for row in rows if row["edge"] == name and row["kind"] == "point"]
        assert len(points) == len(edge["s"]) > 0
        assert edge["s"].tolist() == [float(p["s"]) for p in points]
        assert edge["d"].tolist() == [float(p["d"]) for p in points]
    summary = json.loads((cli_dir / "summary.json").read_text())
    assert without_timings(r.summary) == without_timings(summary)
    for name, coefficients in summary["edge_coefficients"].items():
        assert r.edges[name]["coefficients"].tolist() == coefficients
    assert r.summary["centre_sag_m"] == r.centre_sag
    assert set(r.summary["units"]) == set(summary["units"])

    # The files result.write() writes are the command's.
    for name in SAME_BYTES:
        assert (py_dir / name).read_bytes() == (cli_dir / name).read_bytes(), name
    assert without_timings(json.loads((py_dir / "summary.json").read_text())) == \
        without_timings(summary)
    m_cli = json.loads((cli_dir / "manifest.json").read_text())
    m_py = json.loads((py_dir / "manifest.json").read_text())
    assert m_py["options"] == m_cli["options"] and m_py["git_commit"] == m_cli["git_commit"]
    assert sorted(os.listdir(py_dir)) == sorted(os.listdir(cli_dir))


def test_run_options_as_the_flags(cli, tmp_path):
    status, _, err = run_cli(cli, "drape", "--out", str(tmp_path), "--quiet", "--integrator",
                             "cvode-bdf", "--rtol", "1e-7", "--max-order", "3",
                             "--newton-solver", "klu", "--no-pictures")
    assert status == 0, err
    r = knitsim.drape(integrator="cvode-bdf", rtol=1e-7, max_order=3, newton_solver="klu")
    ids, xyz = nodes(tmp_path)
    assert np.array_equal(r.positions[ids], xyz)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert without_timings(r.summary) == without_timings(summary)
    assert r.summary["options"]["rtol"] == 1e-7


def test_write_without_pictures_and_into_a_reused_folder(tmp_path):
    r = knitsim.drape()
    r.write(tmp_path, pictures=True)
    assert (tmp_path / "drape.png").exists()
    r.write(str(tmp_path), pictures=False)  # the same folder again: a stale picture goes
    assert not (tmp_path / "drape.png").exists()
    assert (tmp_path / "nodes.csv").exists()


def test_scene_file_and_path_like(tmp_path):
    scene = tmp_path / "soft.toml"
    scene.write_text('[model]\nstiffness = 600.0\n')
    a = knitsim.drape(scene)
    b = knitsim.drape("four_corner", {"model.stiffness": 600.0})
    assert a.scene == "soft" and np.array_equal(a.positions, b.positions)
    assert a.summary["source"] == str(scene)


def test_numpy_values_are_the_same_overrides():
    k = np.linspace(500.0, 1200.0, 7)[3]  # numpy.float64
    a = knitsim.drape("four_corner", {"model.stiffness": k, "model.seed": np.int64(2)})
    b = knitsim.drape("four_corner", {"model.stiffness": float(k), "model.seed": 2})
    assert np.array_equal(a.positions, b.positions)
    assert a.summary["params"]["stiffness"] == float(k)
