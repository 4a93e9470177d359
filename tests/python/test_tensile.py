"""knitsim.tensile gives `knitsim tensile`'s curve bit for bit and result.write() its files (but
the step_NNN/ folders; timings aside); bad input raises ValueError with the CLI's one-line message
naming the flag; a cancel or Ctrl-C ends the test with status interrupted."""
import csv
import json
import os

import numpy as np
import pytest

import knitsim
from conftest import ROOT, run_cli, run_python

# The test's options as keyword arguments and as the command's flags.
SMALL = dict(steps=3, strain=0.05)
SMALL_FLAGS = ["--steps", "3", "--strain", "0.05", "--set", "knit.contact=0"]
CURVE = ["step", "strain", "displacement_m", "force_N", "force_per_width_N_per_m",
         "lateral_strain", "energy_J"]


def without_timings(value):
    """summary.json without its timings (*wall_seconds, *cpu_seconds at any depth)."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items()
                if not (k.endswith("wall_seconds") or k.endswith("cpu_seconds"))
                or k == "max_wall_seconds"}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


@pytest.fixture
def plain(tmp_path):
    """A 6 x 8 plain chart in a file."""
    path = tmp_path / "plain6x8.chart"
    path.write_text("# 6 courses of 8 knit stitches\n" + "KKKKKKKK\n" * 6)
    return str(path)


def cli_tensile(cli, tmp_path, chart, *flags):
    out = tmp_path / "cli"
    status, _, err = run_cli(cli, "tensile", "--chart", chart, *flags, "--out", str(out),
                             "--quiet")
    assert status == 0, err
    return out


@pytest.mark.parametrize("direction,unload", [("wale", False), ("course", True)])
def test_curve_and_files_are_the_clis(cli, tmp_path, plain, direction, unload):
    flags = SMALL_FLAGS + ["--direction", direction] + (["--unload"] if unload else [])
    cli_dir = cli_tensile(cli, tmp_path, plain, *flags)
    r = knitsim.tensile(plain, {"knit.contact": 0}, direction=direction, unload=unload, **SMALL)
    assert r.status == "complete" and r.complete

    with open(cli_dir / "tensile.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == (7 if unload else 4)
    assert r.step.tolist() == [int(row["step"]) for row in rows]
    for name in CURVE[1:]:
        column = getattr(r, name)
        assert column.dtype == np.float64 and len(column) == len(rows)
        assert column.tolist() == [float(row[name]) for row in rows], name  # bit for bit
    assert r.step_status.tolist() == [row["status"] for row in rows]
    assert r.newton_steps.tolist() == [int(row["newton_steps"]) for row in rows]
    assert list(r.curve) == list(rows[0].keys())
    assert r.reactions[:, 1, 1 if direction == "wale" else 0].tolist() == \
        [float(row["reaction_moving_" + ("y" if direction == "wale" else "x") + "_N"])
         for row in rows]
    assert r.force_N[-1 if not unload else 3] > 0  # the strip pulled is in tension

    summary = json.loads((cli_dir / "summary.json").read_text())
    assert without_timings(r.summary) == without_timings(summary)
    assert r.summary["status"] == r.status and r.summary["units"]

    # The kept steps' positions (outputs=3), as the CLI's step_NNN/points.csv.
    kept = sorted(int(name[5:]) for name in os.listdir(cli_dir) if name.startswith("step_"))
    assert len(kept) == 3 and sorted(r.states) == kept
    for step in kept:
        with open(cli_dir / f"step_{step:03d}" / "points.csv") as f:
            points = list(csv.DictReader(f))
        assert np.array_equal(r.states[step], [[float(p[c]) for c in "xyz"] for p in points])
        assert np.array_equal(r.rest_positions,
                              [[float(p[c + "0"]) for c in "xyz"] for p in points])

    py_dir = tmp_path / "py"
    assert r.write(py_dir, pictures=True) == str(py_dir)
    assert (py_dir / "tensile.csv").read_bytes() == (cli_dir / "tensile.csv").read_bytes()
    assert (py_dir / "tensile.png").stat().st_size > 0
    assert without_timings(json.loads((py_dir / "summary.json").read_text())) == \
        without_timings(summary)
    mine = json.loads((py_dir / "manifest.json").read_text())
    theirs = json.loads((cli_dir / "manifest.json").read_text())
    assert mine["options"] == theirs["options"] and mine["options"]["steps"] == 3
    assert mine["git_commit"] == theirs["git_commit"]
    assert not any(name.startswith("step_") for name in os.listdir(py_dir))  # documented


@pytest.mark.parametrize("kwargs,flags,message", [
    (dict(steps=0), ["--steps", "0"], "--steps = 0: "),
    (dict(strain=2.0), ["--strain", "2"], "--strain = 2: "),
    (dict(direction="diagonal"), ["--direction", "diagonal"], "--direction"),
    (dict(gauge_ratio=-1.0), ["--gauge-ratio", "-1"], "--gauge-ratio"),
    (dict(overrides={"knit.pins": "top"}), ["--set", "knit.pins=top"], "knit.pins: "),
    (dict(rtol=-1), ["--rtol", "-1"], "--rtol = -1: "),
])
def test_bad_input_raises_the_clis_message(cli, tmp_path, plain, kwargs, flags, message):
    with pytest.raises(ValueError) as e:
        knitsim.tensile(plain, **kwargs)
    assert str(e.value).startswith(message), str(e.value)
    status, out, err = run_cli(cli, "tensile", "--chart", plain, *flags,
                               "--out", str(tmp_path / "no"))
    assert status == 2 and err.strip() == "knitsim: error: " + str(e.value)
    assert not (tmp_path / "no").exists()


def test_bad_python_values(plain):
    with pytest.raises(ValueError, match="--integrator = cvode-bdf"):
        knitsim.tensile(plain, integrator="cvode-bdf")
    with pytest.raises(ValueError, match="chart_or_scene: expected a str or os.PathLike"):
        knitsim.tensile(3)
    with pytest.raises(TypeError):
        knitsim.tensile(plain, steps="many")


def test_cancel_ends_the_test_with_status_interrupted(plain):
    cancel = knitsim.Cancel()
    cancel.set()
    r = knitsim.tensile(plain, {"knit.contact": 0}, cancel=cancel, **SMALL)
    assert r.status == "interrupted" and not r.complete
    assert r.step_status.tolist()[-1] == "interrupted"
    assert r.summary["status"] == "interrupted"


def test_ctrl_c_raises_keyboard_interrupt_with_the_partial_curve():
    script = """
import json, os, signal, threading, time
import knitsim
threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
start = time.monotonic()
try:
    knitsim.tensile(%r, steps=100000, outputs=0)
    print(json.dumps({"raised": None}))
except KeyboardInterrupt as e:
    r = e.result
    print(json.dumps({"raised": "KeyboardInterrupt", "status": r.status, "rows": len(r.step),
                      "last": r.step_status.tolist()[-1], "seconds": time.monotonic() - start}))
""" % os.path.join(ROOT, "models", "charts", "plain_jersey.chart")
    p = run_python(script, timeout=300)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["raised"] == "KeyboardInterrupt", out
    assert out["status"] == out["last"] == "interrupted"
    assert 1 < out["rows"] < 100001 and out["seconds"] < 30, out


def test_help_lists_the_tests_options_and_keys():
    doc = knitsim.tensile.__doc__
    for word in ("direction", "gauge_ratio", "unload", "step_NNN", "knit.contact", "ValueError"):
        assert word in doc, word


def test_threads_give_the_same_curve(plain):
    import threading
    one = knitsim.tensile(plain, {"knit.contact": 0}, **SMALL)
    results = [None] * 4

    def work(k):
        results[k] = knitsim.tensile(plain, {"knit.contact": 0}, **SMALL)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        assert r.status == "complete"
        assert r.force_N.tolist() == one.force_N.tolist()
        assert r.energy_J.tolist() == one.energy_J.tolist()
