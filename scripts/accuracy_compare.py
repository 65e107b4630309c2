#!/usr/bin/env python3
"""How sure the accuracy figures of scripts/accuracy.sh are, and whether one run beats another.

    scripts/accuracy_compare.py RUN                 # each pooled figure with its 90 % interval
    scripts/accuracy_compare.py BASE NEW            # NEW - BASE, paired, with its 90 % interval
    ... --scenes yard-1,random-3                    # those scenes only

RUN, BASE and NEW are folders that scripts/accuracy.sh wrote (OUT/<set>, e.g.
out/accuracy/tuning): one sub-folder per scene with labels.json, grid.json and footprints.json.
Two runs are compared on the scenes both hold.

A pooled figure is a ratio of sums over the scenes (every sample of every scene counts once). Its
uncertainty is dominated by which scenes the set happens to hold: a few obstacles make most of a
scene's truly blocked footprints, and footprints next to each other share their verdicts. So the
interval comes from resampling whole scenes (a cluster bootstrap: 2000 draws of as many scenes as
the set holds, with replacement, seeded so that a rerun prints the same figures), and a
comparison draws the same scenes for both runs (paired), which cancels what the scenes have in
common. The verdict column says which run is better where the interval of the difference excludes
0, and "within noise" where it does not.

Unsafe and falsely blocked count only answers of a class. A change that turns answers undecided
(class 4: the map saw a surface it cannot judge) lowers both without telling a planner more: the
rows "free answered drivable" (what a planner may use), "blocked answered non-traversable" and
"blocked answered undecided" show such a shift.
"""
import json
import os
import random
import sys

WITHIN_M = 10.0
DRAWS = 2000
LEVEL = 0.90


def load(path):
    return json.load(open(path)) if os.path.exists(path) else None


def within(doc):
    """The confusion matrix of every sample within WITHIN_M of the path (None without bands)."""
    found = None
    for band in (doc or {}).get("by_distance_from_path", {}).get("bands", []):
        if band["to_m"] <= WITHIN_M + 1e-9:
            found = band.get("metrics_within", {}).get("confusion")
    return found


def confusions(scene_dir):
    """The scene's confusion matrices (rows truth, columns answer; classes 0..4) by source."""
    labels = load(os.path.join(scene_dir, "labels.json"))
    grid = load(os.path.join(scene_dir, "grid.json"))
    feet = load(os.path.join(scene_dir, "footprints.json"))
    return {
        "labels": labels["metrics"]["confusion"] if labels else None,
        "cells10": within(grid),
        "feet": feet["metrics"]["confusion"] if feet else None,
        "feet10": within(feet),
    }


def ratio(n, d):
    return n / d if d else None


def accuracy(m):
    return ratio(sum(m[c][c] for c in (1, 2, 3)), sum(sum(m[t]) for t in (1, 2, 3)))


def unsafe(m):  # truly non-traversable answered traversable or semi
    return ratio(m[3][1] + m[3][2], sum(m[3]))


def falsely_blocked(m):  # truly traversable or semi answered non-traversable
    return ratio(m[1][3] + m[2][3], sum(m[1]) + sum(m[2]))


def non_recall(m):
    return ratio(m[3][3], sum(m[3]))


def blocked_undecided(m):  # truly non-traversable answered undecided (class 4)
    return ratio(m[3][4], sum(m[3]))


def free_drivable(m):  # truly traversable or semi answered traversable or semi
    return ratio(sum(m[t][a] for t in (1, 2) for a in (1, 2)), sum(m[1]) + sum(m[2]))


def trav_called_non(m):
    return ratio(m[1][3], sum(m[1]))


# name, source, function, unit ("%" or ""), whether lower is better
METRICS = [
    ("footprints unsafe", "feet", unsafe, "%", True),
    ("footprints falsely blocked", "feet", falsely_blocked, "%", True),
    ("footprints free answered drivable", "feet", free_drivable, "%", False),
    ("footprints blocked answered non-traversable", "feet", non_recall, "%", False),
    ("footprints blocked answered undecided", "feet", blocked_undecided, "%", True),
    ("footprints within 10 m unsafe", "feet10", unsafe, "%", True),
    ("footprints within 10 m falsely blocked", "feet10", falsely_blocked, "%", True),
    ("footprints within 10 m free answered drivable", "feet10", free_drivable, "%", False),
    ("map accuracy within 10 m", "cells10", accuracy, "", False),
    ("cells within 10 m unsafe", "cells10", unsafe, "%", True),
    ("cells within 10 m falsely blocked", "cells10", falsely_blocked, "%", True),
    ("labels accuracy", "labels", accuracy, "", False),
    ("labels non-traversable recall", "labels", non_recall, "", False),
    ("labels traversable called non-traversable", "labels", trav_called_non, "%", True),
]


def pooled(runs, picks, source, fn):
    """fn of the sum of the picked scenes' matrices (None when a scene lacks it or fn has no
    samples)."""
    total = None
    for i in picks:
        m = runs[i][source]
        if m is None:
            return None
        total = m if total is None else [[a + b for a, b in zip(ra, rb)] for ra, rb in zip(total, m)]
    return fn(total) if total is not None else None


def interval(values):
    values = sorted(v for v in values if v is not None)
    if not values:
        return None, None
    lo = values[int((1 - LEVEL) / 2 * (len(values) - 1))]
    hi = values[int((1 + LEVEL) / 2 * (len(values) - 1))]
    return lo, hi


def fmt(x, unit, signed=False):
    if x is None:
        return "n/a"
    if unit == "%":
        return ("%+.1f" if signed else "%.1f") % (100 * x) + (" points" if signed else " %")
    return ("%+.3f" if signed else "%.3f") % x


def scenes_of(folder):
    if not os.path.isdir(folder):
        sys.exit("accuracy_compare: %s: no such folder (give OUT/<set> of scripts/accuracy.sh)" % folder)
    found = sorted(d for d in os.listdir(folder) if os.path.isdir(os.path.join(folder, d)) and
                   any(os.path.exists(os.path.join(folder, d, f))
                       for f in ("labels.json", "grid.json", "footprints.json")))
    if not found:
        sys.exit("accuracy_compare: %s: no scene folder with labels.json, grid.json or footprints.json" % folder)
    return found


def main(argv):
    args = argv[1:]
    wanted = None
    if "--scenes" in args:
        at = args.index("--scenes")
        if at + 1 >= len(args):
            sys.exit("accuracy_compare: --scenes needs a comma-separated list of scene folders")
        wanted = args[at + 1].split(",")
        del args[at:at + 2]
    if args and args[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0
    if len(args) not in (1, 2):
        print(__doc__.strip(), file=sys.stderr)
        return 2
    folders = args
    names = scenes_of(folders[0])
    for folder in folders[1:]:
        names = [n for n in names if n in scenes_of(folder)]
    if wanted is not None:
        missing = [n for n in wanted if n not in names]
        if missing:
            sys.exit("accuracy_compare: no scene folder %s in %s" % (", ".join(missing), " and ".join(folders)))
        names = wanted
    if not names:
        sys.exit("accuracy_compare: the two runs share no scene")
    runs = [[confusions(os.path.join(folder, n)) for n in names] for folder in folders]
    rng = random.Random(1)
    draws = [[rng.randrange(len(names)) for _ in names] for _ in range(DRAWS)]
    everything = list(range(len(names)))
    level = "%d %%" % round(100 * LEVEL)
    print("%d scenes (%s); intervals from %d draws of the scenes with replacement." %
          (len(names), ", ".join(names), DRAWS))
    print()
    if len(folders) == 1:
        print("| figure | pooled | %s interval over scenes |" % level)
        print("|---|---:|---|")
        for name, source, fn, unit, _ in METRICS:
            value = pooled(runs[0], everything, source, fn)
            if value is None:
                continue
            lo, hi = interval(pooled(runs[0], d, source, fn) for d in draws)
            print("| %s | %s | %s to %s |" % (name, fmt(value, unit), fmt(lo, unit), fmt(hi, unit)))
        return 0
    print("| figure | base | new | new - base | %s interval of the difference | verdict |" % level)
    print("|---|---:|---:|---:|---|---|")
    for name, source, fn, unit, lower_is_better in METRICS:
        base, new = (pooled(r, everything, source, fn) for r in runs)
        if base is None or new is None:
            continue
        differences = []
        for d in draws:
            a, b = pooled(runs[0], d, source, fn), pooled(runs[1], d, source, fn)
            differences.append(None if a is None or b is None else b - a)
        lo, hi = interval(differences)
        if lo is None or lo <= 0 <= hi:
            verdict = "within noise"
        else:
            verdict = "new better" if (hi < 0) == lower_is_better else "base better"
        print("| %s | %s | %s | %s | %s to %s | %s |" % (
            name, fmt(base, unit), fmt(new, unit), fmt(new - base, unit, True), fmt(lo, unit, True),
            fmt(hi, unit, True), verdict))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
