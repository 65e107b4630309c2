"""Fixtures shared by the Python API's tests: the `ssta` command line of the same build, a small
rendered yard and its map built by the command line, so every binding is checked against the
C++ answer on the same input.

The build folder is SSTA_BUILD_DIR (default: build/ beside python/); its python/ folder is put
on sys.path when PYTHONPATH does not already hold the module."""

import csv
import io
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("SSTA_BUILD_DIR", ROOT / "build")).resolve()
SSTA = BUILD / "apps" / "ssta"

try:
    import ssta  # noqa: F401
except ImportError:
    sys.path.insert(0, str(BUILD / "python"))


def run_cli(*args, check=True):
    """Runs `ssta ARGS...`; returns the CompletedProcess (text). check: fail on a non-zero exit."""
    result = subprocess.run([str(SSTA), *map(str, args)], capture_output=True, text=True)
    if check and result.returncode != 0:
        raise AssertionError(f"ssta {' '.join(map(str, args))} failed: {result.stderr}")
    return result


def cli_error(*args):
    """The one-line message of a failing `ssta ARGS...`, without its "ssta: error: " prefix."""
    result = run_cli(*args, check=False)
    assert result.returncode == 2, result.stderr
    line = result.stderr.strip().splitlines()[-1]
    assert line.startswith("ssta: error: "), line
    return line[len("ssta: error: "):]


# The query CSV's text columns; every other column is a number.
TEXT_COLUMNS = {"decided_by"}


def read_csv(text):
    """CSV text with a header -> {column: array}: float64 ("nan" reads as NaN), str for the
    TEXT_COLUMNS."""
    rows = list(csv.reader(io.StringIO(text)))
    header, body = rows[0], rows[1:]
    return {name: np.array([r[i] if name in TEXT_COLUMNS else float(r[i]) for r in body])
            for i, name in enumerate(header)}


@pytest.fixture(scope="session")
def cli():
    if not SSTA.exists():
        pytest.fail(f"{SSTA} not built (cmake --build {BUILD} --target ssta_cli)")
    return run_cli


@pytest.fixture(scope="session")
def yard(tmp_path_factory, cli):
    """A rendered yard: 6 frames of 320 x 240, about 1 s to render."""
    seq = tmp_path_factory.mktemp("yard") / "yard"
    cli("synth", "--scene", "yard", "--frames", 6, "--width", 320, "--height", 240, "--focal", 210,
        "--seed", 1, "--out", seq)
    return seq


@pytest.fixture(scope="session")
def yard_map(yard, cli, tmp_path_factory):
    """The yard's map, built by `ssta build-map`."""
    path = tmp_path_factory.mktemp("map") / "yard.ot"
    cli("build-map", "--sequence", yard, "--map", path, "-q")
    return path
