#!/usr/bin/env python3
"""Plan a robot's path on an SSTA map, from Python.

Builds the map of a stereo sequence (a rendered yard by default), plans a path with A* over the
exported grid's costs (unknown, undecided and non-traversable cells avoided, with the robot's
size kept clear of them), checks the path with the map's footprint and path queries, and saves
a picture of the map and the path.

    PYTHONPATH=build/python python3 examples/python/plan_on_map.py --out out/plan
    PYTHONPATH=build/python python3 examples/python/plan_on_map.py --sequence SEQ --out out/plan
    PYTHONPATH=build/python python3 examples/python/plan_on_map.py --sequence SEQ --static --out out/plan

Writes OUT/map.ot, OUT/plan.png (the picture) and OUT/plan.json (start, goal, the path's
vertices [m, world frame] and both checks). Exits 1 when no path is found or the check fails,
2 with a one-line message when the sequence cannot be mapped (a recording without poses needs
--static, as `ssta build-map` does).
"""

import argparse
import heapq
import json
import math
import pathlib
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")  # files only: no display needed
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Patch, Polygon  # noqa: E402

import ssta  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", type=pathlib.Path, required=True, help="output folder (created)")
    p.add_argument("--sequence", type=pathlib.Path,
                   help="sequence to map (ASL / EuRoC folder, KITTI raw drive, ROS bag); default: render a yard "
                        "with `ssta synth`")
    p.add_argument("--static", action="store_true",
                   help="the platform stands still and the sequence has no poses: every frame at the origin, "
                        "levelled by gravity (as `ssta build-map --static`); the goal then lies along the "
                        "camera's view (world x)")
    p.add_argument("--ssta", type=pathlib.Path, default=ROOT / "build" / "apps" / "ssta",
                   help="the ssta command line, to render the yard (default: build/apps/ssta)")
    p.add_argument("--robot-length", type=float, default=1.0, help="robot length [m]")
    p.add_argument("--robot-width", type=float, default=0.6, help="robot width [m]")
    p.add_argument("--goal-ahead", type=float, default=10.0,
                   help="the goal lies this far ahead of the sensor's start, along its drive [m]")
    p.add_argument("--goal-right", type=float, default=4.0,
                   help="... and this far to the right of the drive [m]")
    return p.parse_args()


def dilate(mask, radius_px):
    """Cells within radius_px of a True cell (a disc): the obstacles grown by the robot."""
    out = mask.copy()
    h, w = mask.shape
    r = int(math.ceil(radius_px))
    for dv in range(-r, r + 1):
        for du in range(-r, r + 1):
            if dv * dv + du * du > radius_px * radius_px:
                continue
            shifted = np.zeros_like(mask)
            shifted[max(dv, 0):h + min(dv, 0), max(du, 0):w + min(du, 0)] = \
                mask[max(-dv, 0):h + min(-dv, 0), max(-du, 0):w + min(-du, 0)]
            out |= shifted
    return out


def astar(step_cost, start, goal):
    """Cheapest 8-connected path of cells from start to goal (row, col); a move costs its length
    in cells times the mean step_cost of its two cells; inf cells are never entered. None when
    the goal cannot be reached."""
    h, w = step_cost.shape
    moves = [(dv, du, math.hypot(dv, du)) for dv in (-1, 0, 1) for du in (-1, 0, 1) if dv or du]

    def heuristic(cell):  # octile distance: no move costs less than its length
        dv, du = abs(cell[0] - goal[0]), abs(cell[1] - goal[1])
        return max(dv, du) + (math.sqrt(2) - 1) * min(dv, du)

    best = {start: 0.0}
    came_from = {}
    frontier = [(heuristic(start), start)]
    while frontier:
        _, cell = heapq.heappop(frontier)
        if cell == goal:
            path = [cell]
            while cell in came_from:
                cell = came_from[cell]
                path.append(cell)
            return path[::-1]
        for dv, du, length in moves:
            nxt = (cell[0] + dv, cell[1] + du)
            if not (0 <= nxt[0] < h and 0 <= nxt[1] < w) or math.isinf(step_cost[nxt]):
                continue
            g = best[cell] + length * 0.5 * (step_cost[cell] + step_cost[nxt])
            if g < best.get(nxt, math.inf):
                best[nxt] = g
                came_from[nxt] = cell
                heapq.heappush(frontier, (g + heuristic(nxt), nxt))
    return None


def nearest_free(free, grid, xy):
    """The free cell (row, col) whose centre is nearest to xy [m]."""
    v, u = np.nonzero(free)
    x, y = cell_centres(grid, v, u)
    i = int(np.argmin((x - xy[0]) ** 2 + (y - xy[1]) ** 2))
    return int(v[i]), int(u[i])


def cell_centres(grid, v, u):
    """World x, y [m] of cells (row, col): row 0 is the largest y."""
    r = grid["resolution_m"]
    h = grid["class"].shape[0]
    return grid["origin"][0] + (np.asarray(u) + 0.5) * r, grid["origin"][1] + (h - 1 - np.asarray(v) + 0.5) * r


def draw(grid, meta, path_xy, poses, args, checks, out_png):
    colours = {k: np.array(c) / 255.0 for k, c in ssta.CLASS_COLOURS.items()}
    image = np.zeros(grid["class"].shape + (3,))
    for k, c in colours.items():
        image[grid["class"] == k] = 0.35 + 0.65 * c if k != ssta.UNKNOWN else (0.18, 0.18, 0.18)
    fig, ax = plt.subplots(figsize=(9, 6.5), dpi=110)
    ax.imshow(image, extent=grid["extent"], origin="upper", interpolation="nearest")
    sensor = meta["sensor_path"]
    ax.plot(sensor[:, 0], sensor[:, 1], color="black", lw=2, ls="--", label="camera's drive")
    for x, y, yaw in poses[:: max(1, len(poses) // 12)]:
        c, s = math.cos(yaw), math.sin(yaw)
        half = np.array([[args.robot_length, args.robot_width], [args.robot_length, -args.robot_width],
                         [-args.robot_length, -args.robot_width], [-args.robot_length, args.robot_width]]) / 2
        corners = half @ np.array([[c, s], [-s, c]]) + (x, y)
        ax.add_patch(Polygon(corners, closed=True, fill=False, ec="orange", lw=1.0))
    ax.plot(path_xy[:, 0], path_xy[:, 1], color="orange", lw=2.5, label="planned path (A*)")
    ax.plot(*path_xy[0], "o", color="white", mec="black", ms=9, label="start")
    ax.plot(*path_xy[-1], "*", color="yellow", mec="black", ms=15, label="goal")
    legend = [Patch(color=0.35 + 0.65 * colours[k], label=name) for k, name in
              ((1, "traversable"), (2, "semi-traversable"), (3, "non-traversable"))]
    legend.append(Patch(color=(0.18, 0.18, 0.18), label="unknown"))
    handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + legend, loc="upper left", fontsize=8, framealpha=0.9)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"A* on the exported costs, robot {args.robot_length} x {args.robot_width} m: "
                 f"footprints' worst class {checks['footprints_worst']}, "
                 f"{'blocked' if checks['path']['blocked'] else 'not blocked'}", fontsize=10)
    fig.tight_layout()
    fig.savefig(out_png)
    plt.close(fig)


def main():
    args = parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    sequence = args.sequence
    if sequence is None:
        sequence = args.out / "yard"
        subprocess.run([str(args.ssta), "synth", "--scene", "yard", "--frames", "20", "--seed", "1",
                        "--out", str(sequence)], check=True, stdout=subprocess.DEVNULL)

    try:
        summary = ssta.build_map(sequence, args.out / "map.ot", static_platform=args.static)
    except (ssta.Error, FileNotFoundError) as e:  # bad input: the library's one-line message
        print(f"plan_on_map.py: error: {e}", file=sys.stderr)
        return 2
    print(f"map: {summary['frames_used']} frames fused into {args.out / 'map.ot'}")
    the_map = ssta.Map.open(args.out / "map.ot")
    meta = the_map.metadata

    # The planner's grid: the exported classes and costs (holes filled as the export fills them).
    grid = the_map.project(as_exported=True)
    classes, cost = grid["class"], grid["cost"]
    drivable = (classes == ssta.TRAVERSABLE) | (classes == ssta.SEMI_TRAVERSABLE)
    # Keep the robot's half diagonal clear of everything else (unknown included) and prefer
    # cheap ground: a step costs 1 on traversable ground, up to 1 + 4 x 0.75 on the worst semi.
    half_diagonal_px = 0.5 * math.hypot(args.robot_length, args.robot_width) / grid["resolution_m"]
    free = ~dilate(~drivable, half_diagonal_px)
    step_cost = np.where(free, 1.0 + 4.0 * np.nan_to_num(cost, nan=1.0), np.inf)

    # Start where the camera started, goal ahead along its drive: the nearest free cells.
    sensor = meta["sensor_path"][:, :2]
    heading = sensor[-1] - sensor[0]
    if np.linalg.norm(heading) < grid["resolution_m"]:  # a static platform: along its view, world x
        heading = np.array([1.0, 0.0])
    heading /= np.linalg.norm(heading)
    start = nearest_free(free, grid, sensor[0])
    right = np.array([heading[1], -heading[0]])
    goal = nearest_free(free, grid, sensor[0] + args.goal_ahead * heading + args.goal_right * right)
    cells = astar(step_cost, start, goal)
    if cells is None:
        print("no path: the goal cannot be reached over known drivable ground", file=sys.stderr)
        return 1
    v, u = np.array(cells).T
    path_xy = np.column_stack(cell_centres(grid, v, u))

    # Check it with the map itself: a footprint at every cell of the path, heading along it, and
    # the path with the robot's width, both as the exported grid shows the ground.
    ahead = np.vstack([path_xy[1:], path_xy[-1:]]) - np.vstack([path_xy[:1], path_xy[:-1]])
    yaw = np.arctan2(ahead[:, 1], ahead[:, 0])
    poses = np.column_stack([path_xy, yaw])
    footprints = the_map.footprints(poses, args.robot_length, args.robot_width, as_exported=True)
    path_check = the_map.path(path_xy, args.robot_width, as_exported=True)
    worst = int(footprints["worst"].max())
    checks = {
        "footprints_worst": worst,
        "footprints_fully_observed": bool((footprints["observed_cells"] == footprints["cells"]).all()),
        "path": {k: path_check[k] for k in ("worst", "blocked", "length_m", "fraction_observed", "mean_cost")},
    }
    valid = worst in (ssta.TRAVERSABLE, ssta.SEMI_TRAVERSABLE) and not path_check["blocked"]

    draw(grid, meta, path_xy, poses, args, checks, args.out / "plan.png")
    plan = {"start": path_xy[0].tolist(), "goal": path_xy[-1].tolist(), "path": path_xy.tolist(),
            "robot": {"length_m": args.robot_length, "width_m": args.robot_width}, "checks": checks,
            "valid": valid}
    (args.out / "plan.json").write_text(json.dumps(plan, indent=1))
    print(f"path: {path_check['length_m']:.1f} m, footprints' worst class {worst}, "
          f"{'blocked' if path_check['blocked'] else 'not blocked'}; picture {args.out / 'plan.png'}")
    return 0 if valid else 1


if __name__ == "__main__":
    sys.exit(main())
