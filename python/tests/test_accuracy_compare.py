"""scripts/accuracy_compare.py on run folders written here, whose figures are known: pooled
ratios, intervals that shrink to the value when every scene agrees, and paired verdicts."""

import json
import subprocess
import sys

from conftest import ROOT

SCRIPT = ROOT / "scripts" / "accuracy_compare.py"


def footprints(blocked, unsafe, free, falsely_blocked):
    """A footprints.json whose confusion matrix holds `blocked` truly blocked footprints,
    `unsafe` of them answered traversable, and `free` truly traversable ones, `falsely_blocked`
    of them answered non-traversable."""
    m = [[0] * 5 for _ in range(5)]
    m[3][3], m[3][1] = blocked - unsafe, unsafe
    m[1][1], m[1][3] = free - falsely_blocked, falsely_blocked
    return {"metrics": {"confusion": m}}


def write_run(folder, scenes):
    """scenes: name -> (blocked, unsafe, free, falsely blocked)."""
    for name, counts in scenes.items():
        (folder / name).mkdir(parents=True)
        (folder / name / "footprints.json").write_text(json.dumps(footprints(*counts)))
    return folder


def run(*folders):
    result = subprocess.run([sys.executable, str(SCRIPT), *map(str, folders)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    rows = {}
    for line in result.stdout.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if line.startswith("| footprints"):
            rows[cells[0]] = cells[1:]
    return rows


def test_one_run_pools_the_scenes_and_its_interval_spans_them(tmp_path):
    # 10 % and 30 % unsafe in two scenes of 100 truly blocked footprints each: 20 % pooled.
    # Drawing two scenes with replacement pools 10, 20 or 30 %: the 90 % interval is 10 to 30.
    rows = run(write_run(tmp_path / "a", {"s1": (100, 10, 1000, 50), "s2": (100, 30, 1000, 50)}))
    assert rows["footprints unsafe"] == ["20.0 %", "10.0 % to 30.0 %"]
    # Every scene blocks 5 % of its free footprints: every draw does too.
    assert rows["footprints falsely blocked"] == ["5.0 %", "5.0 % to 5.0 %"]
    # The rest of the free footprints are answered drivable, the rest of the blocked ones
    # non-traversable, none undecided.
    assert rows["footprints free answered drivable"] == ["95.0 %", "95.0 % to 95.0 %"]
    assert rows["footprints blocked answered non-traversable"][0] == "80.0 %"
    assert rows["footprints blocked answered undecided"] == ["0.0 %", "0.0 % to 0.0 %"]


def test_answers_turned_undecided_show_as_a_loss_where_unsafe_and_falsely_blocked_do_not(tmp_path):
    base = write_run(tmp_path / "base", {"s%d" % i: (50, 10, 500, 25) for i in range(4)})
    # Every scene answers 20 of its 25 falsely blocked free footprints undecided instead.
    undecided = tmp_path / "undecided"
    for i in range(4):
        doc = footprints(50, 10, 500, 25)
        m = doc["metrics"]["confusion"]
        m[1][3], m[1][4] = 5, 20
        (undecided / ("s%d" % i)).mkdir(parents=True)
        (undecided / ("s%d" % i) / "footprints.json").write_text(json.dumps(doc))
    rows = run(base, undecided)
    assert rows["footprints falsely blocked"][2:] == ["-4.0 points", "-4.0 points to -4.0 points", "new better"]
    assert rows["footprints free answered drivable"][2:] == ["+0.0 points", "+0.0 points to +0.0 points",
                                                             "within noise"]


def test_a_difference_every_scene_shows_is_a_verdict_and_one_scene_alone_is_noise(tmp_path):
    scenes = {"s%d" % i: (50, 10, 500, 25) for i in range(6)}
    base = write_run(tmp_path / "base", scenes)
    # Every scene loses 5 of its 10 unsafe footprints: 10 points better in every draw.
    better = write_run(tmp_path / "better", {k: (50, 5, 500, 25) for k in scenes})
    rows = run(base, better)
    assert rows["footprints unsafe"] == ["20.0 %", "10.0 %", "-10.0 points", "-10.0 points to -10.0 points",
                                         "new better"]
    assert rows["footprints falsely blocked"][2:] == ["+0.0 points", "+0.0 points to +0.0 points", "within noise"]
    # One scene of six gets worse by 30 footprints, three better by 10 each: the pooled figure
    # is the same, and the draws go either way.
    mixed = dict(scenes, s0=(50, 40, 500, 25), s1=(50, 0, 500, 25), s2=(50, 0, 500, 25), s3=(50, 0, 500, 25))
    rows = run(base, write_run(tmp_path / "mixed", mixed))
    assert rows["footprints unsafe"][2] == "+0.0 points"
    assert rows["footprints unsafe"][4] == "within noise"
