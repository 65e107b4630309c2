#!/usr/bin/env python3
"""A 1M-point map query from Python (ssta.Map.query) against the same query in C++
(query_benchmark_cpp: TopSurfaceAt into the same rows, no Python), on the same map and points.

    PYTHONPATH=build/python python3 python/benchmarks/query_benchmark.py [--map MAP.ot] [--points N]

Without --map it renders the demo's yard (20 frames, `ssta synth`) and builds its map first.
Prints the best of --repeats runs of each and their ratio (docs/python.md)."""

import argparse
import math
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import ssta

ROOT = pathlib.Path(__file__).resolve().parents[2]


def grid_points(bounds, n):
    """n points of a side x side grid over the map's bounds, as query_benchmark.cpp makes them."""
    x0, y0, _, x1, y1, _ = bounds
    side = math.ceil(math.sqrt(n))
    i = np.arange(n)
    return np.column_stack([x0 + (i % side) / side * (x1 - x0), y0 + (i // side) / side * (y1 - y0)])


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--map", type=pathlib.Path, help="map to query (default: build the demo's yard)")
    p.add_argument("--points", type=int, default=1_000_000)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--build", type=pathlib.Path, default=ROOT / "build", help="the build folder")
    args = p.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        map_path = args.map
        if map_path is None:
            seq = pathlib.Path(tmp) / "yard"
            subprocess.run([str(args.build / "apps" / "ssta"), "synth", "--scene", "yard", "--frames", "20",
                            "--seed", "1", "--out", str(seq)], check=True, stdout=subprocess.DEVNULL)
            map_path = pathlib.Path(tmp) / "yard.ot"
            ssta.build_map(seq, map_path)
        the_map = ssta.Map.open(map_path)
        points = grid_points(the_map.bounds, args.points)

        python_s = math.inf
        for _ in range(args.repeats):
            start = time.perf_counter()
            rows = the_map.query(points)
            python_s = min(python_s, time.perf_counter() - start)
        cpp = subprocess.run([str(args.build / "python" / "query_benchmark_cpp"), str(map_path), str(args.points),
                              str(args.repeats)], check=True, capture_output=True, text=True).stdout.split()
        cpp_s, cpp_observed = float(cpp[0]), int(cpp[1])
        if cpp_observed != int(rows["observed"].sum()):
            sys.exit(f"the two queries disagree: {cpp_observed} vs {int(rows['observed'].sum())} observed")

    print(f"map {map_path.name if args.map else 'the demo yard'}: {args.points} points, "
          f"{int(rows['observed'].sum())} on an observed surface; best of {args.repeats}")
    print(f"C++     {cpp_s * 1e3:8.1f} ms  ({cpp_s / args.points * 1e9:.0f} ns/point)")
    print(f"Python  {python_s * 1e3:8.1f} ms  ({python_s / args.points * 1e9:.0f} ns/point)")
    print(f"ratio   {python_s / cpp_s:8.2f}  (Python / C++)")


if __name__ == "__main__":
    main()
