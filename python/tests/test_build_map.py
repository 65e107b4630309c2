"""ssta.build_map against `ssta build-map`: the same map and summary, Ctrl-C and errors."""

import fcntl
import json
import os
import shutil
import signal

import numpy as np
import pytest

import ssta
from conftest import cli_error


def grid_points(the_map):
    x0, y0, _, x1, y1, _ = the_map.bounds
    xs, ys = np.meshgrid(np.arange(x0, x1, 0.1) + 0.05, np.arange(y0, y1, 0.1) + 0.05)
    return np.column_stack([xs.ravel(), ys.ravel()])


def test_map_and_summary_equal_cli(yard, yard_map, cli, tmp_path):
    calls = []
    summary = ssta.build_map(yard, tmp_path / "py.ot", progress=lambda done, total: calls.append((done, total)))
    assert calls == [(i, 6) for i in range(1, 7)]
    cli("build-map", "--sequence", yard, "--map", tmp_path / "cli.ot", "--json", tmp_path / "cli.json", "-q")
    expected = json.loads((tmp_path / "cli.json").read_text())
    for volatile in ("wall_s",):
        expected.pop(volatile)
        summary.pop(volatile)
    assert summary.pop("map_path") == str(tmp_path / "py.ot")
    assert summary == expected
    assert summary["frames_used"] == 6
    python_map, cli_map = ssta.Map.open(tmp_path / "py.ot"), ssta.Map.open(yard_map)
    points = grid_points(cli_map)
    a, b = python_map.query(points), cli_map.query(points)
    for name in a.dtype.names:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_config_files_and_objects(yard, tmp_path):
    (tmp_path / "strict.yaml").write_text("vehicle:\n  max_slope_deg: 10\n  semi_slope_deg: 5\n")
    ssta.build_map(yard, tmp_path / "file.ot", tmp_path / "strict.yaml", max_frames=2)
    assert ssta.Map.open(tmp_path / "file.ot").metadata["vehicle"]["max_slope_deg"] == 10.0
    config = ssta.Config()
    config.vehicle.max_step_m = 0.3
    summary = ssta.build_map(yard, tmp_path / "object.ot", config, max_frames=2, sequential=True)
    assert summary["frames_used"] == 2
    assert ssta.Map.open(tmp_path / "object.ot").metadata["vehicle"]["max_step_m"] == 0.3


def test_resume_continues_the_map(yard, tmp_path):
    ssta.build_map(yard, tmp_path / "m.ot", max_frames=3)
    summary = ssta.build_map(yard, tmp_path / "m.ot", resume=True)
    assert summary["frames_already_in_map"] == 3 and summary["frames_used"] == 3
    assert ssta.Map.open(tmp_path / "m.ot").metadata["frames_inserted"] == 6


@pytest.fixture
def ctrl_c_raises():
    # A shell starts background jobs (as CI may run this suite) with SIGINT ignored, and Python
    # then leaves it ignored: install its own handler, as an interactive session has it.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_stops_after_the_frame_and_saves(yard, tmp_path, ctrl_c_raises):
    def interrupt_after_two(done, total):
        if done == 2:
            os.kill(os.getpid(), signal.SIGINT)  # as Ctrl-C on the terminal

    with pytest.raises(KeyboardInterrupt):
        ssta.build_map(yard, tmp_path / "stopped.ot", progress=interrupt_after_two, sequential=True)
    stopped = ssta.Map.open(tmp_path / "stopped.ot").metadata
    assert stopped["frames_inserted"] == 2  # the frames before the stop, saved
    summary = ssta.build_map(yard, tmp_path / "stopped.ot", resume=True)
    assert summary["frames_already_in_map"] == 2 and summary["frames_used"] == 4


def test_an_exception_in_progress_stops_and_is_raised(yard, tmp_path):
    def fail_at_three(done, total):
        if done == 3:
            raise RuntimeError("planner says stop")

    with pytest.raises(RuntimeError, match="planner says stop"):
        ssta.build_map(yard, tmp_path / "m.ot", progress=fail_at_three)
    assert ssta.Map.open(tmp_path / "m.ot").metadata["frames_inserted"] == 3


def test_errors_name_the_file_or_argument(yard, tmp_path, cli):
    with pytest.raises(FileNotFoundError) as e:
        ssta.build_map(tmp_path / "no_sequence", tmp_path / "m.ot")
    assert e.value.filename == str(tmp_path / "no_sequence")
    with pytest.raises(FileNotFoundError) as e:
        ssta.build_map(yard, tmp_path / "m.ot", [tmp_path / "missing.yaml"])
    assert e.value.filename == str(tmp_path / "missing.yaml")
    with pytest.raises(FileNotFoundError) as e:
        ssta.build_map(yard, tmp_path / "no_folder" / "m.ot")
    assert e.value.filename == str(tmp_path / "no_folder")
    with pytest.raises(ValueError, match=r"^map_path: .* is a folder"):
        ssta.build_map(yard, tmp_path)
    with pytest.raises(ValueError, match=r"^every: "):
        ssta.build_map(yard, tmp_path / "m.ot", every=0)
    with pytest.raises(ValueError, match=r"^progress: expected a callable"):
        ssta.build_map(yard, tmp_path / "m.ot", progress=3)
    with pytest.raises(ValueError, match=r"^config: expected None, an ssta.Config"):
        ssta.build_map(yard, tmp_path / "m.ot", config=3)
    # Bad input the library finds: the command line's message.
    (tmp_path / "bad.yaml").write_text("vehicle:\n  max_step_m: -1\n")
    with pytest.raises(ssta.Error) as e:
        ssta.build_map(yard, tmp_path / "m.ot", tmp_path / "bad.yaml")
    assert str(e.value) == cli_error("build-map", "--sequence", yard, "--map", tmp_path / "m.ot",
                                     "--config", tmp_path / "bad.yaml", "-q")
    assert not (tmp_path / "m.ot").exists()


def test_one_writer_per_map(yard, tmp_path):
    # The lock build-map takes: flock(2) on MAP.lock, which names its holder.
    ssta.build_map(yard, tmp_path / "m.ot", max_frames=2)
    with open(tmp_path / "m.ot.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        lock.write(f"pid {os.getpid()}: a test\n")
        lock.flush()
        with pytest.raises(ssta.Error) as e:
            ssta.build_map(yard, tmp_path / "m.ot", resume=True)
        assert str(e.value).startswith(f"{tmp_path / 'm.ot'}: another process is writing this map "
                                       f"(pid {os.getpid()}: a test)")
    assert ssta.Map.open(tmp_path / "m.ot").metadata["frames_inserted"] == 2
    ssta.build_map(yard, tmp_path / "m.ot", resume=True)
    assert ssta.Map.open(tmp_path / "m.ot").metadata["frames_inserted"] == 6


def test_a_recording_the_map_holds_is_refused_unless_allowed(yard, tmp_path):
    shutil.copytree(yard, tmp_path / "again")
    ssta.build_map(yard, tmp_path / "m.ot", every=2)
    recordings = ssta.Map.open(tmp_path / "m.ot").metadata["recordings"]
    assert [(r["sequence"], r["frames"]) for r in recordings] == [(os.path.basename(yard), 3)]
    with pytest.raises(ssta.Error, match=r"already holds the recording .* and 'again' shares its frame at"):
        ssta.build_map(tmp_path / "again", tmp_path / "m.ot", resume=True)
    assert ssta.Map.open(tmp_path / "m.ot").metadata["frames_inserted"] == 3
    ssta.build_map(tmp_path / "again", tmp_path / "m.ot", resume=True, allow_overlap=True)
    recordings = ssta.Map.open(tmp_path / "m.ot").metadata["recordings"]
    assert [r["frames"] for r in recordings] == [3, 6]
