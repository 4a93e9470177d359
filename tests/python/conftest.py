"""pytest set-up for the Python module's tests (tests/python/, ctest python_module).

ctest runs them with Debian's /usr/bin/python3 -m pytest, PYTHONPATH=<build>/python, and
KNITSIM_CLI=<build>/knitsim (the binary the module is compared with). KNITSIM_PYTHON_BUILT=1 says
the build made the module: then a module that does not import is a failure. Without it (the
sanitizer build does not make the module: docs/python.md) the session ends with exit status 77,
which ctest reports as skipped.
"""
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def pytest_sessionstart(session):
    try:
        import knitsim  # noqa: F401
    except ImportError as e:
        if os.environ.get("KNITSIM_PYTHON_BUILT") == "1":
            raise
        pytest.exit(f"skipped: the knitsim module is not built ({e}); build it with "
                    "./run.sh --build-only (not built under --sanitize: docs/python.md)",
                    returncode=77)


@pytest.fixture(scope="session")
def cli():
    """The knitsim binary of the same build."""
    path = os.environ.get("KNITSIM_CLI", os.path.join(ROOT, "build", "knitsim"))
    if not os.access(path, os.X_OK):
        pytest.fail(f"no knitsim binary at {path} (set KNITSIM_CLI)")
    return path


def run_cli(cli, *args):
    """Runs the binary; returns (exit status, stdout, stderr)."""
    p = subprocess.run([cli, *args], capture_output=True, text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def run_python(code, timeout=600):
    """Runs `code` in a fresh interpreter (this one) with the same environment."""
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=timeout)
