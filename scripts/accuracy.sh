#!/usr/bin/env bash
# Accuracy of the shipped defaults on scenes with exact truth: per-frame labels (`ssta classify`
# + `ssta eval labels`) and the map (`ssta build-map` + `export --format grid` + `eval grid`),
# per scene, as a Markdown table. JSON per run in out/accuracy/<set>/.
#
#   scripts/accuracy.sh tuning [FRAMES] [-- extra args for classify and build-map]
#   scripts/accuracy.sh wide [FRAMES] [-- ...]
#   scripts/accuracy.sh report [FRAMES] [-- ...]
#
# Fixed sets of scenes. Settings are chosen on the tuning set, and checked on the wide set
# (the named scenes' seed 2 and twelve more `random` ones) that they do not only fit those
# twelve; the report set is read only to report the result, so a figure on it says how the
# method does on terrain it was not tuned on. Each set has the four named scenes and `random`
# ones (terrain, rig and light drawn from the seed: docs/accuracy.md). FRAMES defaults to 60.
# Columns: per-frame label accuracy, non-traversable recall and the share of traversable
# pixels called non-traversable; the map grid's accuracy within 10 m of the path and its
# unsafe / falsely blocked cells there; what a planner is told: unsafe / falsely blocked robot
# footprints (eval footprints --as-exported), over all seen ground and within 10 m. The last
# row pools the samples of every scene. A second table pools the footprints per 2 m band of
# distance from the path, with each class's recall; a third counts the missed footprints by
# the map's rule at the cell that makes each a miss; a fourth what a planner that drives only
# on footprints answered at least this confident (bars 0.4 to 0.99) is told; a fifth splits the
# map's cells within 10 m of the path by true class and answer, as shares of all of them (where
# the accuracy goes); a sixth the per-frame labels' pixels per 5 m band of true depth from the
# camera.
# SCENES="yard:1 random:3" runs those scenes only; MAP_ONLY=1 skips the per-frame labels;
# DISPARITY=1 (not with MAP_ONLY) also scores the matcher's disparity of every frame against
# the true one (classify --disparity + eval disparity: out/accuracy/<set>/<scene>/disparity.json)
# and adds a table per scene: wrong or missing disparities (D1), end-point error, and how much of
# each depth edge's near side (a lip, a pit's rim, an obstacle's top) the matcher gave the far
# side's disparity;
# PADDING=0.1 asks the map about footprints padded by 0.1 m on every side (eval footprints
# --padding), as a planner that pads its robot would. Each scene's unsafe and falsely blocked
# footprints are listed in out/accuracy/<set>/<scene>/footprint_misses.csv, nearest the path
# first, each with that cell and what the map says there. A last table gives each pooled
# figure's 90 % interval over the set's scenes (scripts/accuracy_compare.py, which also says
# whether one run beats another: pass it both runs' out/accuracy/<set> folders).
# Needs a built tree (build/apps/ssta): scripts/test.sh or scripts/demo.sh builds it.
set -euo pipefail
caller_dir=$PWD  # where relative paths among the args are read from
cd "$(dirname "$0")/.."
# SSTA (the binary that classifies and maps) and SSTA_SYNTH (the one that renders) let two
# builds be compared on the same rendered scenes.
ssta=${SSTA:-build/apps/ssta}
synth=${SSTA_SYNTH:-$ssta}
. scripts/scene_sets.sh
parse_set_args 60 "$@"
out=${OUT:-out/accuracy}/$set_name
seqs=${SEQS:-out/accuracy/sequences}  # rendered once, shared by every run
mkdir -p "$out" "$seqs"

if [ -n "${SCENES:-}" ]; then read -r -a runs <<< "$SCENES"; fi

for run in "${runs[@]}"; do
  scene=${run%%:*}
  seed=${run##*:}
  name=$scene-$seed
  seq=$seqs/$name-$frames
  mkdir -p "$out/$name"
  # Rendered once, and again when an older renderer's truth left the cells along class
  # boundaries unscored (gt/grid.yaml without seen: both_cameras; synth overwrites its own runs).
  if [ ! -f "$seq/gt/rig.yaml" ] || ! grep -q '^seen: both_cameras' "$seq/gt/grid.yaml" 2>/dev/null; then
    "$synth" synth --scene "$scene" --seed "$seed" --frames "$frames" --out "$seq" >/dev/null
  fi
  echo "accuracy: $name" >&2
  if [ -z "${MAP_ONLY:-}" ]; then
    "$ssta" classify --sequence "$seq" --out "$out/$name/classified" -q ${DISPARITY:+--disparity} "${args[@]}"
    "$ssta" eval labels --pred "$out/$name/classified" --gt "$seq" --json "$out/$name/labels.json" >/dev/null
    if [ -n "${DISPARITY:-}" ]; then
      "$ssta" eval disparity --pred "$out/$name/classified" --gt "$seq/gt" --json "$out/$name/disparity.json" >/dev/null
    fi
  fi
  "$ssta" build-map --sequence "$seq" --map "$out/$name/map.ot" -q "${args[@]}" >/dev/null
  "$ssta" export --map "$out/$name/map.ot" --format grid --out "$out/$name/grid" >/dev/null
  "$ssta" eval grid --pred "$out/$name/grid" --gt "$seq" --json "$out/$name/grid.json" >/dev/null
  "$ssta" eval footprints --map "$out/$name/map.ot" --gt "$seq" --as-exported ${PADDING:+--padding "$PADDING"} \
    --json "$out/$name/footprints.json" --misses "$out/$name/footprint_misses.csv" >/dev/null
done

python3 - "$out" "$seqs" "$frames" "${runs[@]}" <<'PY'
import os, sys
sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, "scripts")
from accuracy_compare import load, within  # the same reading of the JSON the intervals use
out, seqs, frames, runs = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]

def confusion(metrics):
    return metrics["confusion"] if metrics else None

def add(a, b):
    return b if a is None else [[x + y for x, y in zip(ra, rb)] for ra, rb in zip(a, b)]

def scored(m):
    """Samples whose truth is a class (1..3)."""
    return sum(sum(m[t]) for t in (1, 2, 3))

def rates(m):
    """accuracy, non-traversable recall, unsafe, falsely blocked (shares; None without samples)."""
    if m is None:
        return None, None, None, None
    correct = sum(m[c][c] for c in (1, 2, 3))
    blocked, free = sum(m[3]), sum(m[1]) + sum(m[2])
    ratio = lambda n, d: n / d if d else None
    return (ratio(correct, scored(m)), ratio(m[3][3], blocked), ratio(m[3][1] + m[3][2], blocked),
            ratio(m[1][3] + m[2][3], free))

def f(x, pct=False):
    if x is None:
        return "n/a"
    return "%.1f %%" % (100 * x) if pct else "%.3f" % x

print("| scene | rig f / b / h | labels acc | labels non-trav recall | labels trav. called non | "
      "map acc within 10 m | cells within 10 m: unsafe / falsely blocked | "
      "footprints: unsafe / falsely blocked | footprints within 10 m: unsafe / falsely blocked |")
print("|---|---|---|---|---|---|---|---|---|")
totals = {}
for run in runs:
    scene, seed = run.split(":")
    name = "%s-%s" % (scene, seed)
    d, seq = os.path.join(out, name), os.path.join(seqs, "%s-%s" % (name, frames))
    labels, grid, feet = load(d + "/labels.json"), load(d + "/grid.json"), load(d + "/footprints.json")
    mats = {"labels": confusion(labels and labels["metrics"]), "cells10": within(grid),
            "feet": confusion(feet and feet["metrics"]), "feet10": within(feet)}
    for k, m in mats.items():
        if m is not None:
            totals[k] = add(totals.get(k), m)
    rig = dict(l.split(": ", 1) for l in open(seq + "/gt/rig.yaml") if ": " in l and not l.startswith("#"))
    rig = "%.0f / %.2f / %.2f" % (float(rig["focal_px"]), float(rig["baseline_m"]), float(rig["camera_height_m"]))
    la, lr, _, _ = rates(mats["labels"])
    lm = mats["labels"]
    trav_non = (lm[1][3] / sum(lm[1])) if lm and sum(lm[1]) else None
    ca, _, cu, cf = rates(mats["cells10"])
    _, _, fu, ff = rates(mats["feet"])
    _, _, wu, wf = rates(mats["feet10"])
    print("| %s | %s | %s | %s | %s | %s | %s / %s | %s / %s | %s / %s |" % (
        name, rig, f(la), f(lr), f(trav_non, True), f(ca), f(cu, True), f(cf, True), f(fu, True), f(ff, True),
        f(wu, True), f(wf, True)))
lm = totals.get("labels")
la, lr, _, _ = rates(lm)
trav_non = (lm[1][3] / sum(lm[1])) if lm and sum(lm[1]) else None
ca, _, cu, cf = rates(totals.get("cells10"))
_, _, fu, ff = rates(totals.get("feet"))
_, _, wu, wf = rates(totals.get("feet10"))
print("| **pooled** | | **%s** | **%s** | **%s** | **%s** | **%s / %s** | **%s / %s** | **%s / %s** |" % (
    f(la), f(lr), f(trav_non, True), f(ca), f(cu, True), f(cf, True), f(fu, True), f(ff, True), f(wu, True),
    f(wf, True)))

# What a planner is told by distance from the path, pooled over the scenes: per 2 m band the
# footprints' unsafe and falsely blocked shares and each class's recall (labels: over all pixels).
def recalls(m):
    return " / ".join(f(m[c][c] / sum(m[c]) if m and sum(m[c]) else None) for c in (1, 2, 3))

def pooled_bands(file_name, section):
    """The scenes' confusion matrices per band of a JSON's `section`, summed: {(from, to): m}."""
    bands = {}
    for run in runs:
        doc = load(os.path.join(out, "%s-%s" % tuple(run.split(":")), file_name))
        for band in (doc or {}).get(section, {}).get("bands", []):
            key = (band["from_m"], band["to_m"])
            bands[key] = add(bands.get(key), band["metrics"]["confusion"])
    return bands

def band_table(title, blocked, where, bands):
    print()
    print("| %s | scored | %s | unsafe | falsely blocked | recall trav. / semi / non |" % (title, blocked))
    print("|---|---|---|---|---|---|")
    for key in sorted(bands):
        m = bands[key]
        _, _, u, fb = rates(m)
        print("| %g-%g m from the %s | %d | %d | %s | %s | %s |" % (
            key[0], key[1], where, scored(m), sum(m[3]), f(u, True), f(fb, True), recalls(m)))

band_table("footprints, pooled", "truly blocked", "path", pooled_bands("footprints.json", "by_distance_from_path"))
m = totals.get("feet")
if m:
    _, _, u, fb = rates(m)
    print("| **all** | **%d** | **%d** | **%s** | **%s** | **%s** |" % (
        scored(m), sum(m[3]), f(u, True), f(fb, True), recalls(m)))
# Which of the map's rules decided the cell that makes each missed footprint a miss (eval
# footprints' misses_by_rule: an unsafe one's truly blocked cell, a falsely blocked one's red
# cell; `ssta explain` names the rules), pooled over the scenes.
by_rule = {}
for run in runs:
    doc = load(os.path.join(out, "%s-%s" % tuple(run.split(":")), "footprints.json"))
    for row in (doc or {}).get("misses_by_rule", []):
        counts = by_rule.setdefault(row["rule"], [0, 0, 0])
        counts[0] += row["unsafe"]
        counts[1] += row["falsely_blocked"]
        counts[2] += row["falsely_blocked_by_a_true_obstacle"]
if by_rule:
    print()
    print("| the map's rule at a missed footprint's cell | unsafe footprints | falsely blocked footprints "
          "| of which by a true obstacle at the edge |")
    print("|---|---|---|---|")
    for rule, (u, fb, edge) in sorted(by_rule.items(), key=lambda kv: -(kv[1][0] + kv[1][1])):
        print("| %s | %d | %d | %d |" % (rule, u, fb, edge))
# What a planner that drives only on footprints answered at least this confident is told (eval
# footprints' by_min_confidence): the truly blocked it would drive into, the truly free it would
# drive on, pooled over the scenes. The bar is the planner's; the map's classes stay.
bars = {}
blocked_free = [0, 0]
for run in runs:
    doc = load(os.path.join(out, "%s-%s" % tuple(run.split(":")), "footprints.json"))
    if not doc or "by_min_confidence" not in doc:
        continue
    m = confusion(doc["metrics"])
    blocked_free[0] += sum(m[3])
    blocked_free[1] += sum(m[1]) + sum(m[2])
    for row in doc["by_min_confidence"]:
        counts = bars.setdefault(row["min_confidence"], [0, 0])
        counts[0] += row["unsafe"]
        counts[1] += row["free_drivable"]
if bars and all(blocked_free):
    print()
    print("| footprints, pooled: drive only on answers at least this confident | unsafe | free answered drivable |")
    print("|---|---|---|")
    for bar, (u, d) in sorted(bars.items()):
        print("| %.2f | %s | %s |" % (bar, f(u / blocked_free[0], True), f(d / blocked_free[1], True)))
# Where the map's cells within 10 m of the path go wrong, pooled: each true class by the map's
# answer as a share of all scored cells, so the three diagonal entries add up to the pooled map
# accuracy and every other entry is what that confusion costs it (unknown: no surface was
# observed in the column, even after the export's fill).
m = totals.get("cells10")
if m and scored(m):
    n = scored(m)
    print()
    print("| map cells within 10 m, pooled: truth | cells | answered unknown | traversable | semi "
          "| non-traversable | undecided |")
    print("|---|---|---|---|---|---|---|")
    for c, name in ((1, "traversable"), (2, "semi-traversable"), (3, "non-traversable")):
        print("| %s | %d | %s |" % (name, sum(m[c]), " | ".join(f(m[c][a] / n, True) for a in range(5))))
if lm:
    print()
    print("Per-frame labels, pooled: recall trav. / semi / non %s." % recalls(lm))
    # The same pixels by their true depth from the camera (eval labels' depth bands).
    depth = pooled_bands("labels.json", "by_depth")
    if depth:
        band_table("per-frame labels, pooled", "truly non-traversable", "camera", depth)

# The matcher against the true disparity (DISPARITY=1), per scene and pooled over the pixels of
# every frame: a lip whose near side takes the far side's disparity reads as a rounded slope.
rows = []
for run in runs:
    name = "%s-%s" % tuple(run.split(":"))
    doc = load(os.path.join(out, name, "disparity.json"))
    if doc:
        doc["epe_sum"] = doc["epe_px"] * doc["matched_pixels"]  # pools by matched pixels
        rows.append((name, doc))
if rows:
    keys = ("truth_pixels", "matched_pixels", "bad_matched_pixels", "behind_edge_pixels", "fattened_pixels",
            "front_edge_pixels", "eroded_pixels", "epe_sum")
    pooled = {k: sum(doc[k] for _, doc in rows) for k in keys}
    def matcher_row(name, d, bold=""):
        ratio = lambda n, t: n / t if t else None
        epe = ratio(d["epe_sum"], d["matched_pixels"])
        cells = (name, f(ratio(d["truth_pixels"] - d["matched_pixels"] + d["bad_matched_pixels"], d["truth_pixels"]), True),
                 f(ratio(d["bad_matched_pixels"], d["matched_pixels"]), True), "n/a" if epe is None else "%.2f" % epe,
                 f(ratio(d["matched_pixels"], d["truth_pixels"]), True),
                 f(ratio(d["fattened_pixels"], d["behind_edge_pixels"]), True),
                 f(ratio(d["eroded_pixels"], d["front_edge_pixels"]), True))
        return "| " + " | ".join(bold + c + bold for c in cells) + " |"
    print()
    print("| matcher against the true disparity | D1 all | D1 matched | EPE [px] | density "
          "| edges: fattened | edges: eroded (near side given the far side's) |")
    print("|---|---|---|---|---|---|---|")
    for name, doc in rows:
        print(matcher_row(name, doc))
    print(matcher_row("pooled", pooled, bold="**"))
PY

echo
names=()
for run in "${runs[@]}"; do names+=("${run%%:*}-${run##*:}"); done
python3 scripts/accuracy_compare.py "$out" --scenes "$(IFS=,; echo "${names[*]}")"
