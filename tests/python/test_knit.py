"""knitsim.knit gives `knitsim knit`'s numbers bit for bit, and result.write() its files byte for
byte (timings aside: the wall and CPU seconds in summary.json, manifest.json's time and command
line); a bad chart raises ValueError naming its row and column; a knit scene runs."""
import csv
import json
import math
import os

import numpy as np
import pytest

import knitsim
from conftest import ROOT, run_cli

CHART = os.path.join(ROOT, "models", "charts", "single_tuck.chart")
SCENE = os.path.join(ROOT, "models", "knit_scenes", "single_tuck.toml")
# Every file but summary.json and manifest.json (compared as JSON below) must match byte for byte.
JSON_FILES = {"summary.json", "manifest.json"}


def without_timings(value):
    """summary.json without its timings (*wall_seconds, *cpu_seconds at any depth)."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items()
                if not (k.endswith("wall_seconds") or k.endswith("cpu_seconds"))
                or k == "max_wall_seconds"}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


def files(folder):
    """Every file under `folder`, relative."""
    out = []
    for base, _, names in os.walk(folder):
        out += [os.path.relpath(os.path.join(base, n), folder) for n in names]
    return sorted(out)


def points_csv(folder):
    with open(os.path.join(folder, "points.csv")) as f:
        rows = list(csv.DictReader(f))
    ids = np.array([int(r["id"]) for r in rows])
    now = np.array([[float(r[c]) for c in ("x", "y", "z")] for r in rows])
    rest = np.array([[float(r[c]) for c in ("x0", "y0", "z0")] for r in rows])
    return ids, now, rest


def same_as_the_cli(r, cli_dir, py_dir):
    ids, now, rest = points_csv(cli_dir)
    assert r.positions.shape == (len(ids), 3)
    assert np.array_equal(ids, np.arange(len(ids)))
    assert np.array_equal(r.positions, now) and np.array_equal(r.rest_positions, rest)
    assert not np.array_equal(r.positions, r.rest_positions)  # the run moved the points

    summary = json.loads((cli_dir / "summary.json").read_text())
    assert without_timings(r.summary) == without_timings(summary)
    for block in ("units", "yarn", "fabric"):
        assert r.summary[block] and block in summary
    assert r.summary["status"] == r.status

    # centerlines.csv: per course, its samples.
    with open(cli_dir / "centerlines.csv") as f:
        rows = list(csv.DictReader(f))
    courses = sorted({int(row["course"]) for row in rows})
    assert len(r.centerlines) == len(courses) == summary["courses"]
    for c, line in enumerate(r.centerlines):
        mine = [row for row in rows if int(row["course"]) == c]
        assert line.shape == (len(mine), 3)
        assert np.array_equal(line, [[float(row[k]) for k in "xyz"] for row in mine])
        assert r.centerline_u[c].tolist() == [float(row["u"]) for row in mine]

    # stitches.csv: a column per field.
    with open(cli_dir / "stitches.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(r.stitches) == list(rows[0].keys())
    for name, column in r.stitches.items():
        assert len(column) == len(rows)
        for value, row in zip(column, rows):
            text = row[name]
            if name == "stitch":
                assert value == text
            elif name in ("wale", "course", "held_over"):
                assert column.dtype.kind == "i"
                assert value == int(text)
            elif text == "":
                assert math.isnan(value)
            else:
                assert value == float(text), (name, value, text)

    # The files result.write() writes are the command's.
    assert r.write(py_dir, pictures=False) == str(py_dir)
    assert files(py_dir) == files(cli_dir)
    for name in files(cli_dir):
        if name not in JSON_FILES:
            assert (py_dir / name).read_bytes() == (cli_dir / name).read_bytes(), name
    assert without_timings(json.loads((py_dir / "summary.json").read_text())) == \
        without_timings(summary)
    m_cli = json.loads((cli_dir / "manifest.json").read_text())
    m_py = json.loads((py_dir / "manifest.json").read_text())
    for key in ("options", "params", "chart", "integrator", "frames", "git_commit"):
        assert m_py.get(key) == m_cli.get(key), key


def test_chart_same_numbers_and_files_as_the_cli(cli, tmp_path):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    status, _, err = run_cli(cli, "knit", "--chart", CHART, "--no-pictures", "--quiet",
                             "--out", str(cli_dir))
    assert status == 0, err
    r = knitsim.knit(CHART)
    assert r.status == "equilibrium" and r.chart == "single_tuck"
    assert r.summary["chart_file"] == CHART
    assert r.stitches["stitch"].tolist().count("T") == 1
    same_as_the_cli(r, cli_dir, py_dir)


def test_overrides_and_run_options_as_the_flags(cli, tmp_path):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    status, _, err = run_cli(cli, "knit", "--chart", CHART, "--no-pictures", "--quiet",
                             "--set", "knit.contact=0", "--integrator", "cvode-bdf",
                             "--rtol", "1e-7", "--frames", "3", "--out", str(cli_dir))
    assert status == 0, err
    r = knitsim.knit(CHART, {"knit.contact": 0}, "cvode-bdf", frames=3, rtol=1e-7)
    assert r.summary["options"]["rtol"] == 1e-7 and len(r.summary["frames"]) == 3
    same_as_the_cli(r, cli_dir, py_dir)


def test_knit_scene_runs_as_the_cli(cli, tmp_path):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    status, _, err = run_cli(cli, "knit", "--scene", SCENE, "--no-pictures", "--quiet",
                             "--out", str(cli_dir))
    assert status == 0, err
    r = knitsim.knit(SCENE)
    assert r.status == "equilibrium"
    same_as_the_cli(r, cli_dir, py_dir)
    # The scene is the chart at its defaults: the same points as the chart itself.
    assert np.array_equal(r.positions, knitsim.knit(CHART).positions)


def test_bad_chart_raises_the_cli_message(cli, tmp_path):
    chart = tmp_path / "bad.chart"
    chart.write_text("KKKK\nKKXK\nKKKK\n")
    status, _, err = run_cli(cli, "knit", "--chart", str(chart), "--quiet",
                             "--out", str(tmp_path / "out"))
    assert status == 2
    with pytest.raises(ValueError) as e:
        knitsim.knit(str(chart))
    message = str(e.value)
    assert "row" in message and "column 3" in message, message
    assert message in err  # the CLI's one line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("call,words", [
    (lambda: knitsim.knit(CHART, {"knit.wale_stiffness": -1}), "knit.wale_stiffness"),
    (lambda: knitsim.knit(CHART, {"model.nope": 1}), "model.nope"),
    (lambda: knitsim.knit(CHART, integrator="nope"), "--integrator"),
    (lambda: knitsim.knit(CHART, frames=0), "--frames"),
    (lambda: knitsim.knit(CHART, rtol="x"), "--rtol"),
    (lambda: knitsim.knit("/nonexistent/x.chart"), "/nonexistent/x.chart"),
    (lambda: knitsim.knit(3), "chart_or_scene"),
])
def test_bad_input_raises_value_error(call, words):
    with pytest.raises(ValueError) as e:
        call()
    assert words in str(e.value)


def test_cancel_ends_the_run_with_its_status():
    cancel = knitsim.Cancel()
    cancel.set()
    r = knitsim.knit(CHART, cancel=cancel)
    assert r.status == "interrupted"
    assert r.positions.shape == r.rest_positions.shape


def test_threads_give_the_same_points():
    import threading
    one = knitsim.knit(CHART)
    results = [None] * 4

    def run(i):
        results[i] = knitsim.knit(CHART)

    threads = [threading.Thread(target=run, args=(i,)) for i in range(len(results))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        assert np.array_equal(r.positions, one.positions)
        assert without_timings(r.summary) == without_timings(one.summary)


def test_help_lists_the_knit_keys():
    doc = knitsim.knit.__doc__
    knit_keys = [k for k in knitsim.list_keys() if k["key"].startswith("knit.")]
    assert knit_keys
    for k in knit_keys:
        line = next(l for l in doc.splitlines() if l.strip().startswith(k["key"] + " ("))
        assert k["unit"] in line and "default " + k["default"] in line and k["accepted"] in line
    assert "model.stiffness (" not in doc  # the drape's keys are not the knit's
