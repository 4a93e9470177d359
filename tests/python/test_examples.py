"""The worked examples of docs/examples/ run headless (matplotlib's Agg backend) and say what
they should: the sweep's sag falls as the stiffness rises; the fit finds a finite objective."""
import csv
import os

from conftest import ROOT, run_python

EXAMPLES = os.path.join(ROOT, "docs", "examples")


def run_example(name, *args):
    code = ("import runpy, sys; sys.argv = [%r] + %r; runpy.run_path(%r, run_name='__main__')"
            % (name, list(args), os.path.join(EXAMPLES, name)))
    p = run_python(code)
    assert p.returncode == 0, p.stderr
    return p.stdout


def test_stiffness_sweep(tmp_path):
    run_example("stiffness_sweep.py", "--out", str(tmp_path), "--points", "5")
    assert (tmp_path / "sag_vs_stiffness.png").stat().st_size > 10000
    with open(tmp_path / "sag_vs_stiffness.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 10 and all(r["status"] == "equilibrium" for r in rows)
    for topology in "ab":
        sag = [float(r["centre_sag_m"]) for r in rows if r["topology"] == topology]
        assert sag == sorted(sag, reverse=True) and sag[-1] < sag[0]


def test_fit_lab_data(tmp_path):
    out = run_example("fit_lab_data.py", "--out", str(tmp_path), "--decades", "2")
    assert "objective" in out
    assert (tmp_path / "fit_edges.png").stat().st_size > 10000
    assert (tmp_path / "fitted_drape" / "nodes.csv").exists()


def test_knit_loops(tmp_path):
    out = run_example("knit_loops.py", "--out", str(tmp_path))
    assert "single_tuck: equilibrium" in out
    assert (tmp_path / "knit_loops.png").stat().st_size > 10000
    with open(tmp_path / "knit_loops.csv") as f:
        rows = {r["stitch"]: r for r in csv.DictReader(f)}
    assert sorted(rows) == ["K", "T"] and rows["T"]["cells"] == "1"
    assert rows["K"]["cells"] == str(8 * 6 - 1)
