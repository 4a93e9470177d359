"""Every way a call can go wrong: bad input raises ValueError with the CLI's one-line message;
a run that fails numerically returns its status; nothing crashes or exits the interpreter."""
import os

import pytest

import knitsim
from conftest import run_cli, run_python


def cli_message(cli, *args):
    """The one-line message the CLI prints for bad input (exit status 2)."""
    status, _, err = run_cli(cli, "drape", "--quiet", "--no-pictures", *args)
    assert status == 2, err
    line = err.strip().splitlines()[-1]
    assert line.startswith("knitsim: error: ")
    return line[len("knitsim: error: "):]


# (the call's arguments, the same input on the command line)
SAME_AS_CLI = [
    (dict(overrides={"model.stiffness": -5}), ["--set", "model.stiffness=-5"]),
    (dict(overrides={"model.stifness": 900}), ["--set", "model.stifness=900"]),
    (dict(overrides={"model.stiffness": "abc"}), ["--set", "model.stiffness=abc"]),
    (dict(overrides={"model.topology": "d"}), ["--set", "model.topology=d"]),
    (dict(overrides={"model.seed": -1}), ["--set", "model.seed=-1"]),
    (dict(overrides=["model.stiffness"]), ["--set", "model.stiffness"]),
    (dict(scene="no_such_scene"), ["--scene", "no_such_scene"]),
    (dict(scene="/nonexistent/x.toml"), ["--scene", "/nonexistent/x.toml"]),
    (dict(integrator="foo"), ["--integrator", "foo"]),
    (dict(rtol=-1), ["--rtol", "-1"]),
    (dict(max_wall=-1), ["--max-wall", "-1"]),
    (dict(target="/nonexistent/t.csv"), ["--target", "/nonexistent/t.csv"]),
]


@pytest.mark.parametrize("kwargs,flags", SAME_AS_CLI)
def test_bad_input_is_a_value_error_with_the_cli_message(cli, tmp_path, kwargs, flags):
    with pytest.raises(ValueError) as e:
        knitsim.drape(**kwargs)
    assert str(e.value) == cli_message(cli, "--out", str(tmp_path / "out"), *flags)
    assert "\n" not in str(e.value)


def test_bad_toml(tmp_path, cli):
    bad = tmp_path / "bad.toml"
    bad.write_text("[model\nstiffness = 1\n")
    with pytest.raises(ValueError) as e:
        knitsim.drape(bad)
    assert str(e.value) == cli_message(cli, "--scene", str(bad), "--out", str(tmp_path / "o"))
    assert "TOML syntax error" in str(e.value)


@pytest.mark.parametrize("kwargs,fragment", [
    (dict(scene=5), "scene: expected a str or os.PathLike, got int"),
    (dict(scene=None), "scene: expected a str or os.PathLike, got NoneType"),
    (dict(overrides=5), "overrides: expected a dict"),
    (dict(overrides="model.stiffness=900"), "overrides: expected a dict"),
    (dict(overrides={5: 900}), "overrides: keys are scene keys as text"),
    (dict(overrides=[900]), "overrides: a list holds \"key=value\" texts"),
    (dict(overrides={"model.stiffness": float("nan")}), "model.stiffness = nan: must be"),
    (dict(overrides={"model.stiffness": float("inf")}), "model.stiffness = inf: must be"),
    (dict(overrides={"model.stiffness": [1, 2]}), "model.stiffness = [1, 2]: must be"),
    (dict(overrides={"model.stiffness": None}), "model.stiffness = None: must be"),
    (dict(overrides={"scene.name": "a\nb"}), "scene.name = a\\x0ab: must be"),
    (dict(integrator=3), "--integrator: expected a name"),
    (dict(cancel=True), "cancel: expected a knitsim.Cancel, got bool"),
    (dict(rtl=1e-8), "rtl: unknown key; did you mean rtol?"),
    (dict(max_steps=1.5), "--max-steps = 1.5: must be an integer"),
    (dict(max_steps=10**30), "--max-steps = 1000000000000000000000000000000: must be an integer"),
    (dict(factorization="lu"), "--factorization = lu: must be one of auto, simplicial, block"),
    (dict(scene="four\0corner"), "scene four\\x00corner: a name or path holds no NUL byte"),
    (dict(target="t\0.csv"), "--target t\\x00.csv: a name or path holds no NUL byte"),
])
def test_bad_python_values(kwargs, fragment):
    with pytest.raises(ValueError) as e:
        knitsim.drape(**kwargs)
    assert fragment in str(e.value)


def test_write_errors(tmp_path):
    r = knitsim.drape(max_steps=1)
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(ValueError, match="--out .*: cannot"):
        r.write(blocker / "sub")
    with pytest.raises(ValueError, match="expected a str or os.PathLike"):
        r.write(3)
    # A folder holding another command's results is refused, as --out refuses it.
    other = tmp_path / "knit"
    other.mkdir()
    (other / "manifest.json").write_text('{"command": "knit"}')
    with pytest.raises(ValueError, match="holds the results of `knitsim knit`"):
        r.write(other)


def test_numerical_failure_is_a_status_not_an_exception():
    r = knitsim.drape(max_steps=1, integrator="cvode-bdf")
    assert r.status == "step_limit" and r.certificate == ""
    assert r.summary["status"] == "step_limit"
    # explicit Euler at a step far beyond its stability limit blows up: diverged.
    r = knitsim.drape(integrator="euler", dt=1.0, overrides={"run.t_max": 1e3})
    assert r.status == "diverged", r.message
    assert r.summary["status"] == "diverged" and r.certificate == ""


def test_nothing_exits_the_interpreter():
    # Every bad call of the list above in one fresh interpreter, which must reach its end.
    p = run_python(
        "import knitsim\n"
        "for kw in [dict(scene=5), dict(rtol=-1), dict(overrides={'x': 1}), dict(integrator='x'),"
        " dict(scene='/dev/zero'), dict(scene='/'), dict(max_wall=float('nan'))]:\n"
        "    try:\n"
        "        knitsim.drape(**kw)\n"
        "    except ValueError as e:\n"
        "        pass\n"
        "print('alive')\n")
    assert p.returncode == 0 and p.stdout.strip() == "alive", p.stderr
