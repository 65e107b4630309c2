"""examples/python/plan_on_map.py runs on a small rendered yard: its path is valid on the map
and its picture is written."""

import json
import math
import shutil
import subprocess
import sys

import numpy as np

import ssta
from conftest import ROOT, SSTA


def test_plan_on_map_example(yard, tmp_path):
    out = tmp_path / "plan"
    env_path = [p for p in sys.path if p]
    result = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "python" / "plan_on_map.py"), "--sequence", str(yard),
         "--out", str(out), "--ssta", str(SSTA), "--goal-ahead", "6", "--goal-right", "0"],
        capture_output=True, text=True, env={"PYTHONPATH": ":".join(env_path), "PATH": "/usr/bin:/bin"})
    assert result.returncode == 0, result.stderr
    picture = (out / "plan.png").read_bytes()
    assert picture[:8] == b"\x89PNG\r\n\x1a\n" and len(picture) > 10_000
    plan = json.loads((out / "plan.json").read_text())
    assert plan["valid"]
    path = np.array(plan["path"])
    assert len(path) > 20 and np.allclose(path[0], plan["start"]) and np.allclose(path[-1], plan["goal"])
    the_map = ssta.Map.open(out / "map.ot")
    r = the_map.resolution_m
    steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
    assert np.all(steps > 0.5 * r) and np.all(steps < math.sqrt(2) * r + 1e-9)  # 8-connected cells
    # Checked again here, not trusting the example: every cell of the path is drivable as
    # exported, and the robot's footprint along it never stands on non-traversable ground.
    cells = the_map.query(path, as_exported=True)
    assert set(np.unique(cells["class"])) <= {ssta.TRAVERSABLE, ssta.SEMI_TRAVERSABLE}
    yaw = np.arctan2(*np.diff(path, axis=0)[:, ::-1].T)
    poses = np.column_stack([path[:-1], yaw])
    robot = plan["robot"]
    worst = the_map.footprints(poses, robot["length_m"], robot["width_m"], as_exported=True)["worst"]
    assert set(np.unique(worst)) <= {ssta.TRAVERSABLE, ssta.SEMI_TRAVERSABLE}
    assert (ssta.NON_TRAVERSABLE in the_map.project(as_exported=True)["class"])  # there was something to avoid


def run_example(*args):
    env_path = [p for p in sys.path if p]
    return subprocess.run(
        [sys.executable, str(ROOT / "examples" / "python" / "plan_on_map.py"), *map(str, args), "--ssta", str(SSTA)],
        capture_output=True, text=True, env={"PYTHONPATH": ":".join(env_path), "PATH": "/usr/bin:/bin"})


def test_plan_on_map_without_poses_says_static_and_maps_with_it(cli, tmp_path):
    seq = tmp_path / "still"
    cli("synth", "--scene", "yard", "--frames", 2, "--width", 320, "--height", 240, "--focal", 210,
        "--seed", 1, "--out", seq)
    for folder in seq.rglob("pose0"):  # a recording without poses
        shutil.rmtree(folder)
    assert not ssta_poses(seq)
    result = run_example("--sequence", seq, "--out", tmp_path / "plan")
    assert result.returncode == 2, result.stderr
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("plan_on_map.py: error: "), result.stderr
    assert "has no poses" in lines[0] and "--static" in lines[0], lines[0]

    result = run_example("--sequence", seq, "--static", "--out", tmp_path / "plan")
    assert "Traceback" not in result.stderr, result.stderr
    assert result.returncode in (0, 1), result.stderr  # 1: no path found; both are answers
    assert "map: 2 frames fused" in result.stdout, result.stdout
    the_map = ssta.Map.open(tmp_path / "plan" / "map.ot")
    # Every frame at the origin: the sensor never moved.
    assert np.ptp(the_map.metadata["sensor_path"], axis=0).max() < 1e-9
    assert (tmp_path / "plan" / "plan.png").exists() or result.returncode == 1


def ssta_poses(seq):
    """Whether `ssta inspect` finds poses in the sequence."""
    out = subprocess.run([str(SSTA), "inspect", "--sequence", str(seq)], capture_output=True, text=True).stdout
    return "poses: none" not in out
