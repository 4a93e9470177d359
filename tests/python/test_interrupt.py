"""Ctrl-C during a call: the run ends with status interrupted, and the call raises
KeyboardInterrupt carrying the partial result as .result. Each test runs in a fresh interpreter
that sends itself SIGINT, so a signal that went astray cannot end this test session."""
import json
import os

from conftest import ROOT, run_python

# A run of several seconds whose every step is short: verlet (explicit, a step every few
# microseconds) on a finer four_corner; max_wall bounds it if the interrupt is missed.
LONG = ("dict(scene='four_corner', integrator='verlet', max_wall=60, "
        "overrides={'model.natural_length': 0.02, 'model.symmetry': 'none'})")

SCRIPT = """
import json, os, signal, threading, time
import knitsim
threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
start = time.monotonic()
try:
    knitsim.drape(**%s)
    print(json.dumps({"raised": None}))
except KeyboardInterrupt as e:
    r = e.result
    print(json.dumps({"raised": "KeyboardInterrupt", "status": r.status,
                      "summary_status": r.summary["status"], "seconds": time.monotonic() - start,
                      "finite": bool((r.positions == r.positions).all()), "n": len(r.positions)}))
"""


def test_ctrl_c_raises_keyboard_interrupt_with_the_partial_result():
    p = run_python(SCRIPT % LONG, timeout=120)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["raised"] == "KeyboardInterrupt", out
    assert out["status"] == out["summary_status"] == "interrupted"
    assert out["finite"] and out["n"] == 26 * 26
    assert out["seconds"] < 30, out  # ended by the interrupt, not by max_wall


def test_the_interrupt_is_the_calls_own():
    # A call on another thread, running while the main thread's call is interrupted, runs on to
    # its equilibrium; Python delivers SIGINT to the main thread only.
    script = """
import json, os, signal, threading
import knitsim
other = {}
def work():
    other["r"] = knitsim.drape('four_corner', {'model.natural_length': 0.025,
                                               'model.symmetry': 'none'}, 'cvode-bdf')
t = threading.Thread(target=work)
t.start()
threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
try:
    knitsim.drape(**%s)
    main = "returned"
except KeyboardInterrupt as e:
    main = e.result.status
t.join()
print(json.dumps({"main": main, "other": other["r"].status}))
""" % LONG
    p = run_python(script, timeout=120)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out == {"main": "interrupted", "other": "equilibrium"}, out


def test_custom_signal_handler_exception_is_raised_with_the_result():
    script = """
import json, os, signal, threading
import knitsim
class Stop(Exception):
    pass
def handler(sig, frame):
    raise Stop()
signal.signal(signal.SIGINT, handler)
threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
try:
    knitsim.drape(**%s)
    print(json.dumps({"raised": None}))
except Stop as e:
    print(json.dumps({"raised": "Stop", "status": e.result.status}))
""" % LONG
    p = run_python(script, timeout=120)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout.strip().splitlines()[-1]) == {"raised": "Stop",
                                                             "status": "interrupted"}


def test_a_cancel_flag_ends_a_run_on_another_thread():
    # Ctrl-C reaches the main thread only; a run on a worker thread is ended by its Cancel.
    import threading
    import time

    import knitsim
    cancel = knitsim.Cancel()
    out = {}

    def work():
        out["r"] = knitsim.drape("four_corner", {"model.natural_length": 0.02,
                                                 "model.symmetry": "none"}, "verlet",
                                 cancel=cancel, max_wall=60)

    t = threading.Thread(target=work)
    start = time.monotonic()
    t.start()
    time.sleep(0.3)
    cancel.set()
    t.join()
    assert out["r"].status == "interrupted" and cancel.is_set()
    assert time.monotonic() - start < 30
    # A Cancel already set stops the next run at its first check; a fresh call has its own flag.
    assert knitsim.drape(cancel=cancel, integrator="cvode-bdf").status == "interrupted"
    assert knitsim.drape(integrator="cvode-bdf").status == "equilibrium"


def test_ctrl_c_ends_a_knit_with_its_partial_result():
    # tucks40 without contact under verlet: many short steps for far longer than the 0.5 s.
    script = """
import json, os, signal, threading, time
import knitsim
threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
start = time.monotonic()
try:
    knitsim.knit(%r, {"knit.contact": 0}, "verlet", max_wall=60)
    print(json.dumps({"raised": None}))
except KeyboardInterrupt as e:
    r = e.result
    print(json.dumps({"raised": "KeyboardInterrupt", "status": r.status,
                      "summary_status": r.summary["status"], "seconds": time.monotonic() - start,
                      "n": len(r.positions)}))
""" % os.path.join(ROOT, "models", "charts", "tucks40.chart")
    p = run_python(script, timeout=120)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["raised"] == "KeyboardInterrupt", out
    assert out["status"] == out["summary_status"] == "interrupted"
    assert out["n"] > 0 and out["seconds"] < 30, out


def test_ctrl_c_ends_a_fit_with_its_summary_and_files(tmp_path):
    # The fit stops at the end of its decade: summary.json's dict says interrupted, no fitted
    # drape, and write() leaves the command's files of an interrupted fit (no drape/).
    script = """
import json, os, signal, threading
import knitsim
ex = os.path.join(%r, "docs", "examples")
threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT)).start()
try:
    knitsim.fit(os.path.join(ex, "lab_targets.csv"), os.path.join(ex, "my_fabric.toml"),
                decades=100000, countries=10, seed=1)
    print(json.dumps({"raised": None}))
except KeyboardInterrupt as e:
    r = e.result
    r.write(%r)
    print(json.dumps({"raised": "KeyboardInterrupt", "status": r.status, "drape": r.drape is None,
                      "summary": r.summary}))
""" % (ROOT, str(tmp_path / "fit"))
    p = run_python(script, timeout=120)
    assert p.returncode == 0, p.stderr
    out = json.loads(p.stdout.strip().splitlines()[-1])
    assert out["raised"] == "KeyboardInterrupt", out
    s = out["summary"]
    assert out["status"] == s["status"] == "interrupted" and out["drape"]
    assert s["fitted_drape_status"] == "not_run" and "units" in s
    assert len(s["history"]) < 100000
    written = tmp_path / "fit"
    assert sorted(os.listdir(written)) == ["history.csv", "manifest.json", "summary.json"]
    assert json.loads((written / "summary.json").read_text()) == s
