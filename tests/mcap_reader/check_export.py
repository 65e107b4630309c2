#!/usr/bin/env python3
"""Compares what read_mcap.js decoded from `ssta export --format mcap` with the map's other
exports: /map cell for cell with the grid export's PGM as map_server reads it (YAML thresholds,
trinary), its metadata with the YAML, the GridMap's layers and layout, the point count with the
CSV export's voxels, the path with the map file's sensor_path.

  check_export.py SUMMARY.json MAP.bin GRID.pgm GRID.yaml VOXELS.csv MAP.ot
Exit status 1 listing every mismatch."""
import json
import re
import sys

summary_path, map_bin, pgm_path, yaml_path, csv_path, map_path = sys.argv[1:7]
summary = json.load(open(summary_path))
problems = []


def expect(what, got, want):
    if got != want:
        problems.append(f"{what}: got {got!r}, expected {want!r}")


def near(what, got, want, tol):
    if abs(got - want) > tol:
        problems.append(f"{what}: got {got!r}, expected {want!r} within {tol}")


def read_pgm(path):
    data = open(path, "rb").read()
    tokens, pos = [], 0
    while len(tokens) < 4:  # P5, width, height, maxval; comments skipped
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        tokens.append(data[pos:end])
        pos = end
    width, height = int(tokens[1]), int(tokens[2])
    return width, height, data[pos + 1:pos + 1 + width * height]


yaml = dict(re.findall(r"^(\w+): (.*)$", open(yaml_path).read(), re.M))
resolution = float(yaml["resolution"])
origin = [float(v) for v in yaml["origin"].strip("[]").split(",")]
occupied_thresh, free_thresh = float(yaml["occupied_thresh"]), float(yaml["free_thresh"])
width, height, pixels = read_pgm(pgm_path)

topics = {
    "/map": "nav_msgs/msg/OccupancyGrid",
    "/traversability": "grid_map_msgs/msg/GridMap",
    "/traversability/voxels": "sensor_msgs/msg/PointCloud2",
    "/sensor_path": "nav_msgs/msg/Path",
    "/tf_static": "tf2_msgs/msg/TFMessage",
}
expect("topics", sorted(summary["topics"]), sorted(topics))
for topic, info in summary["topics"].items():
    expect(f"{topic} type", info["type"], topics.get(topic))
    expect(f"{topic} messages", info["messages"], 1)
    expect(f"{topic} latched (transient local, reliable)", info["latched"], True)

# /map: map_server's reading of the PGM (negate 0: p = (255 - value) / 255; occupied above
# occupied_thresh, free below free_thresh, else unknown), its row 0 the image's last row.
m = summary["map"]
expect("/map width", m["width"], width)
expect("/map height", m["height"], height)
near("/map resolution", m["resolution"], resolution, 1e-6)
near("/map origin x", m["origin"][0], origin[0], 1e-9)
near("/map origin y", m["origin"][1], origin[1], 1e-9)
cells = open(map_bin, "rb").read()
expect("/map cells", len(cells), width * height)
mismatches = 0
for row in range(height):
    for col in range(width):
        p = (255 - pixels[(height - 1 - row) * width + col]) / 255.0
        want = 100 if p > occupied_thresh else 0 if p < free_thresh else -1
        v = cells[row * width + col]
        v = v - 256 if v > 127 else v
        got = 100 if v >= 100 else -1 if v < 0 else 0
        if got != want:
            mismatches += 1
expect("/map cells that differ from the PGM as map_server reads it", mismatches, 0)
expect("/map frame", m["frame_id"], "map")

t = summary["traversability"]
expect("/traversability layers", t["layers"], ["class", "cost", "confidence", "elevation", "slope", "step"])
near("/traversability resolution", t["resolution"], resolution, 1e-9)
near("/traversability length_x", t["length"][0], width * resolution, 1e-6)
near("/traversability length_y", t["length"][1], height * resolution, 1e-6)
near("/traversability centre x", t["position"][0], origin[0] + width * resolution / 2, 1e-6)
near("/traversability centre y", t["position"][1], origin[1] + height * resolution / 2, 1e-6)
for k, layout in enumerate(t["layouts"]):
    expect(f"/traversability layout {k}", layout,
           [["column_index", height, width * height], ["row_index", width, width]])
expect("/traversability cells per layer", t["cells"], [width * height] * 6)
known = sum(1 for b in pixels if b != 205)
expect("/traversability cells with a class 1..3 (the PGM's known cells) <= finite class cells",
       t["finite"][0] >= known, True)
expect("/traversability start indices", t["start_index"], [0, 0])

voxels = sum(1 for _ in open(csv_path)) - 1
v = summary["voxels"]
expect("/traversability/voxels points", v["points"], voxels)
expect("/traversability/voxels fields", v["fields"], ["x", "y", "z", "class", "cost", "confidence"])
expect("/traversability/voxels bytes", v["data_bytes"], v["points"] * v["point_step"])

header = open(map_path, "rb").read(1 << 20).decode("latin-1")
found = re.search(r"^#@ssta sensor_path: \[(.*)\]$", header, re.M)
path = len(found.group(1).split(",")) // 3 if found else 0
expect("/sensor_path poses", summary["sensor_path"]["poses"], path)
expect("/tf_static", summary["tf_static"], [["map", "world"]])

if problems:
    print("check_export: the MCAP does not match the map's exports:\n  " + "\n  ".join(problems))
    sys.exit(1)
print(f"check_export: {summary['file']} matches: {width}x{height} cells, {voxels} voxels, {path} path poses")
