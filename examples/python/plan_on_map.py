#!/usr/bin/env python3
"""Plan a robot's path on an SSTA map, from Python.

Builds the map of a stereo sequence (a rendered yard by default), plans a path with A* over
(x, y, heading) on the exported grid's costs per heading (8 headings: the class cost, raised
where the robot's pitch or roll on the ground under it nears or passes the vehicle's
max_pitch_deg, max_descent_deg or max_roll_deg; unknown, undecided and non-traversable cells
avoided, with the robot's footprint at each heading kept clear of them), checks the path with
the map's footprint and path queries, and saves a picture of the map and the path, with the
cells whose cost depends on the heading.

    PYTHONPATH=build/python python3 examples/python/plan_on_map.py --out out/plan
    PYTHONPATH=build/python python3 examples/python/plan_on_map.py --sequence SEQ --out out/plan
    PYTHONPATH=build/python python3 examples/python/plan_on_map.py --sequence SEQ --static --out out/plan
    PYTHONPATH=build/python python3 examples/python/plan_on_map.py --scene hills --config VEHICLE.yaml --out out/plan

Writes OUT/map.ot, OUT/plan.png (the picture) and OUT/plan.json (start, goal, the path's
vertices [m, world frame] and headings [deg], and the checks). Exits 1 when no path is found or the check fails,
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
    p.add_argument("--scene", default="yard", help="scene rendered when no --sequence is given (`ssta synth --scene`)")
    p.add_argument("--config", type=pathlib.Path, action="append", default=[],
                   help="YAML config for the map (repeatable): e.g. a vehicle section with max_roll_deg")
    p.add_argument("--ssta", type=pathlib.Path, default=ROOT / "build" / "apps" / "ssta",
                   help="the ssta command line, to render the yard (default: build/apps/ssta)")
    p.add_argument("--robot-length", type=float, default=1.0, help="robot length [m]")
    p.add_argument("--robot-width", type=float, default=0.6, help="robot width [m]")
    p.add_argument("--goal-ahead", type=float, default=10.0,
                   help="the goal lies this far ahead of the sensor's start, along its drive [m]")
    p.add_argument("--goal-right", type=float, default=4.0,
                   help="... and this far to the right of the drive [m]")
    return p.parse_args()


def footprint_offsets(length_m, width_m, yaw, resolution_m):
    """(dv, du) of the cells whose squares overlap the robot's rectangle, centred on a cell's
    centre and facing yaw (rad from +x towards +y): the cells the map's footprint query counts.
    Two convex shapes overlap unless one of their edge directions separates them: the square's
    (x, y) or the rectangle's (along, across)."""
    half = 0.5 * resolution_m
    c, s = abs(math.cos(yaw)), abs(math.sin(yaw))
    reach_x = 0.5 * (length_m * c + width_m * s) + half  # the rectangle's half extent + the square's
    reach_y = 0.5 * (length_m * s + width_m * c) + half
    reach_along = 0.5 * length_m + half * (c + s)  # the square's half extent along the rectangle's axes
    reach_across = 0.5 * width_m + half * (c + s)
    r = int(math.ceil(max(reach_x, reach_y) / resolution_m))
    offsets = []
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            x, y = dx * resolution_m, dy * resolution_m
            along = x * math.cos(yaw) + y * math.sin(yaw)
            across = -x * math.sin(yaw) + y * math.cos(yaw)
            if (abs(x) < reach_x - 1e-9 and abs(y) < reach_y - 1e-9 and abs(along) < reach_along - 1e-9
                    and abs(across) < reach_across - 1e-9):
                offsets.append((-dy, dx))  # row 0 is the largest y
    return offsets


def any_under(mask, offsets):
    """Cells from which some offset reaches a True cell of mask: the obstacles grown by the
    robot's footprint (outside the grid counts as clear; the map does not count unseen ground)."""
    out = np.zeros_like(mask)
    h, w = mask.shape
    for dv, du in offsets:
        out[max(-dv, 0):h + min(-dv, 0), max(-du, 0):w + min(-du, 0)] |= \
            mask[max(dv, 0):h + min(dv, 0), max(du, 0):w + min(du, 0)]
    return out


# The lattice's headings: k faces 45 k deg from +x towards +y, and its move is one cell that way
# (dv, du) in the image, whose row 0 is the largest y.
HEADINGS = 8
STEPS = [(0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0), (1, 1)]


def astar(step_cost, start, goal):
    """Cheapest path over the lattice (row, col, heading) from the start cell to the goal cell,
    any heading at either end. step_cost is H x W x 8: the cost of standing on a cell facing
    each heading (inf: never). From heading k the robot moves one cell along heading k - 1, k
    or k + 1 (it turns at most 45 deg a cell) and arrives facing it; a move costs its length in
    cells times the mean step_cost of its two cells at that heading. Returns [(row, col,
    heading)], or None when the goal cannot be reached."""
    h, w, _ = step_cost.shape

    def heuristic(cell):  # octile distance: no move costs less than its length
        dv, du = abs(cell[0] - goal[0]), abs(cell[1] - goal[1])
        return max(dv, du) + (math.sqrt(2) - 1) * min(dv, du)

    best, came_from, frontier = {}, {}, []
    for k in range(HEADINGS):
        if not math.isinf(step_cost[start[0], start[1], k]):
            best[(*start, k)] = 0.0
            heapq.heappush(frontier, (heuristic(start), 0.0, (*start, k)))
    while frontier:
        _, g_here, state = heapq.heappop(frontier)
        v, u, k = state
        if g_here > best[state]:
            continue  # a stale entry: the state was reached more cheaply since
        if (v, u) == goal:
            path = [state]
            while state in came_from:
                state = came_from[state]
                path.append(state)
            return path[::-1]
        for turn in (-1, 0, 1):
            k2 = (k + turn) % HEADINGS
            v2, u2 = v + STEPS[k2][0], u + STEPS[k2][1]
            if not (0 <= v2 < h and 0 <= u2 < w) or math.isinf(step_cost[v2, u2, k2]):
                continue
            length = math.sqrt(2) if k2 % 2 else 1.0
            g = best[state] + length * 0.5 * (step_cost[v, u, k2] + step_cost[v2, u2, k2])
            if g < best.get((v2, u2, k2), math.inf):
                best[(v2, u2, k2)] = g
                came_from[(v2, u2, k2)] = state
                heapq.heappush(frontier, (g + heuristic((v2, u2)), g, (v2, u2, k2)))
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


def draw(grid, meta, path_xy, path_cost, poses, args, checks, out_png):
    """Left: the classes, the path coloured by its cost at the heading it drives, footprints.
    Right: where the heading matters: each cell's highest minus lowest cost over the headings."""
    colours = {k: np.array(c) / 255.0 for k, c in ssta.CLASS_COLOURS.items()}
    image = np.zeros(grid["class"].shape + (3,))
    for k, c in colours.items():
        image[grid["class"] == k] = 0.35 + 0.65 * c if k != ssta.UNKNOWN else (0.18, 0.18, 0.18)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(15, 6.5), dpi=100)
    ax.imshow(image, extent=grid["extent"], origin="upper", interpolation="nearest")
    sensor = meta["sensor_path"]
    ax.plot(sensor[:, 0], sensor[:, 1], color="black", lw=2, ls="--", label="camera's drive")
    for x, y, yaw in poses[:: max(1, len(poses) // 12)]:
        c, s = math.cos(yaw), math.sin(yaw)
        half = np.array([[args.robot_length, args.robot_width], [args.robot_length, -args.robot_width],
                         [-args.robot_length, -args.robot_width], [-args.robot_length, args.robot_width]]) / 2
        corners = half @ np.array([[c, s], [-s, c]]) + (x, y)
        ax.add_patch(Polygon(corners, closed=True, fill=False, ec="orange", lw=1.0))
    drawn = ax.scatter(path_xy[:, 0], path_xy[:, 1], c=path_cost, cmap="plasma", vmin=0, vmax=1, s=10, zorder=3)
    fig.colorbar(drawn, ax=ax, shrink=0.7, label="path: cost at its heading")
    ax.plot(*path_xy[0], "o", color="white", mec="black", ms=9, label="start")
    ax.plot(*path_xy[-1], "*", color="yellow", mec="black", ms=15, label="goal")
    legend = [Patch(color=0.35 + 0.65 * colours[k], label=name) for k, name in
              ((1, "traversable"), (2, "semi-traversable"), (3, "non-traversable"))]
    legend.append(Patch(color=(0.18, 0.18, 0.18), label="unknown"))
    handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + legend, loc="upper left", fontsize=8, framealpha=0.9)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"A* over (x, y, heading), robot {args.robot_length} x {args.robot_width} m: "
                 f"footprints' worst class {checks['footprints_worst']}, "
                 f"{'blocked' if checks['path']['blocked'] else 'not blocked'}", fontsize=10)

    stack = grid["cost_heading"]  # NaN at every heading where the class cost is
    spread = stack.max(axis=2) - stack.min(axis=2)
    shown = ax2.imshow(spread, extent=grid["extent"], origin="upper", interpolation="nearest", cmap="magma",
                       vmin=0, vmax=1)
    fig.colorbar(shown, ax=ax2, shrink=0.7, label="highest - lowest cost over the 8 headings")
    ax2.plot(path_xy[:, 0], path_xy[:, 1], color="cyan", lw=1.5, label="planned path")
    ax2.legend(loc="upper left", fontsize=8)
    ax2.set_xlabel("x [m]")
    vehicle = meta["vehicle"]
    ax2.set_title(f"where the heading matters: {int((spread > 0.05).sum())} cells (climb "
                  f"{vehicle['max_pitch_deg']:g}, descent {vehicle['max_descent_deg']:g}, roll "
                  f"{vehicle['max_roll_deg']:g} deg)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out_png)
    plt.close(fig)


def main():
    args = parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    sequence = args.sequence
    if sequence is None:
        sequence = args.out / args.scene
        subprocess.run([str(args.ssta), "synth", "--scene", args.scene, "--frames", "20", "--seed", "1",
                        "--out", str(sequence)], check=True, stdout=subprocess.DEVNULL)

    try:
        summary = ssta.build_map(sequence, args.out / "map.ot", [str(c) for c in args.config] or None,
                                 static_platform=args.static)
    except (ssta.Error, FileNotFoundError) as e:  # bad input: the library's one-line message
        print(f"plan_on_map.py: error: {e}", file=sys.stderr)
        return 2
    print(f"map: {summary['frames_used']} frames fused into {args.out / 'map.ot'}")
    the_map = ssta.Map.open(args.out / "map.ot")
    meta = the_map.metadata

    # The planner's grid: the exported classes and costs per heading (holes filled as the export
    # fills them), the attitude fitted under the robot's own footprint.
    grid = the_map.project(as_exported=True, headings=HEADINGS,
                           heading_footprint=(args.robot_length, args.robot_width))
    classes, cost = grid["class"], grid["cost_heading"]
    drivable = (classes == ssta.TRAVERSABLE) | (classes == ssta.SEMI_TRAVERSABLE)
    # Keep the robot's footprint at each heading clear of everything else (unknown included) and
    # prefer cheap ground: a step costs 1 on traversable ground, up to 1 + 4 x 0.75 on the worst
    # semi; a heading whose pitch or roll passes the limits (cost 1) is never taken there.
    free = np.stack([~any_under(~drivable, footprint_offsets(args.robot_length, args.robot_width,
                                                             math.radians(45.0 * k), grid["resolution_m"]))
                     for k in range(HEADINGS)], axis=2)
    step_cost = np.where(free & (np.nan_to_num(cost, nan=1.0) < 1.0), 1.0 + 4.0 * cost, np.inf)

    # Start where the camera started, goal ahead along its drive: the nearest free cells.
    sensor = meta["sensor_path"][:, :2]
    heading = sensor[-1] - sensor[0]
    if np.linalg.norm(heading) < grid["resolution_m"]:  # a static platform: along its view, world x
        heading = np.array([1.0, 0.0])
    heading /= np.linalg.norm(heading)
    # Start and goal where the robot may face every heading, so that it can leave and arrive
    # whichever way the path runs (the lattice does not turn on the spot): the nearest such cells.
    any_heading = ~np.isinf(step_cost).any(axis=2)
    start = nearest_free(any_heading, grid, sensor[0])
    right = np.array([heading[1], -heading[0]])
    goal = nearest_free(any_heading, grid, sensor[0] + args.goal_ahead * heading + args.goal_right * right)
    states = astar(step_cost, start, goal)
    if states is None:
        print("no path: the goal cannot be reached over known drivable ground", file=sys.stderr)
        return 1
    v, u, k = np.array(states).T
    path_xy = np.column_stack(cell_centres(grid, v, u))
    path_cost = cost[v, u, k]

    # Check it with the map itself: a footprint at every cell of the path, facing the lattice
    # heading it drives there (its pitch and roll within the vehicle's limits), and the path with
    # the robot's width, both as the exported grid shows the ground.
    poses = np.column_stack([path_xy, np.radians(45.0 * k)])
    footprints = the_map.footprints(poses, args.robot_length, args.robot_width, as_exported=True)
    path_check = the_map.path(path_xy, args.robot_width, as_exported=True)
    worst = int(footprints["worst"].max())
    attitude_ok = bool((footprints["within_limits"] | (footprints["attitude"] == ssta.UNKNOWN)).all())
    checks = {
        "footprints_worst": worst,
        "footprints_fully_observed": bool((footprints["observed_cells"] == footprints["cells"]).all()),
        "attitude_within_limits": attitude_ok,
        "largest_pitch_deg": float(np.nanmax(np.abs(footprints["pitch_deg"]), initial=0.0)),
        "largest_roll_deg": float(np.nanmax(np.abs(footprints["roll_deg"]), initial=0.0)),
        "path": {k: path_check[k] for k in ("worst", "blocked", "length_m", "fraction_observed", "mean_cost")},
    }
    valid = worst in (ssta.TRAVERSABLE, ssta.SEMI_TRAVERSABLE) and not path_check["blocked"] and attitude_ok

    draw(grid, meta, path_xy, path_cost, poses, args, checks, args.out / "plan.png")
    plan = {"start": path_xy[0].tolist(), "goal": path_xy[-1].tolist(), "path": path_xy.tolist(),
            "headings_deg": (45.0 * k).tolist(),
            "robot": {"length_m": args.robot_length, "width_m": args.robot_width}, "checks": checks,
            "valid": valid}
    (args.out / "plan.json").write_text(json.dumps(plan, indent=1))
    print(f"path: {path_check['length_m']:.1f} m, footprints' worst class {worst}, "
          f"{'blocked' if path_check['blocked'] else 'not blocked'}, largest pitch "
          f"{checks['largest_pitch_deg']:.1f} deg, roll {checks['largest_roll_deg']:.1f} deg; "
          f"picture {args.out / 'plan.png'}")
    return 0 if valid else 1


if __name__ == "__main__":
    sys.exit(main())
