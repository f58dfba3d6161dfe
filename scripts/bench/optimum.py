#!/usr/bin/env python3
"""Time of the exact optimum (world.optimum.shortest_path) on imported maps.

    .venv/bin/python scripts/bench/optimum.py MAP [MAP ...] [--repeat 3] [--budget 60]

MAP: a nav2 map ``.yaml`` or a MovingAI ``.map`` (1 m cells), with the importer's default start
and goal and the default robot (turtlebot3-burger, radius 0.105 m). For each map: import time,
polygons, disks (convex vertices of the union), whether the spatial index was used, the optimum
length and the best of ``--repeat`` wall times and CPU times of ``shortest_path`` (the import is
not included). Prints a markdown table and the machine's load average.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path

import numpy as np

from swarmpath.world.importers import load_movingai_map, load_ros_map
from swarmpath.world.optimum import INDEX_ABOVE, _disks, shortest_path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("maps", nargs="+", type=Path)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--budget", type=float, default=60.0, help="seconds per optimum")
    args = parser.parse_args()
    print(f"Python {platform.python_version()}, {os.cpu_count()} CPUs, load average "
          f"{os.getloadavg()[0]:.1f} at the start.\n")
    print("| map | cells | import (s) | polygons | disks | index | optimum (m) | wall (s) | "
          "CPU (s) |\n| --- | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: |")
    for path in args.maps:
        t0 = time.perf_counter()
        imported = (load_movingai_map(path) if path.suffix == ".map" else load_ros_map(path))
        t_import = time.perf_counter() - t0
        s = imported.scenario
        w, h = s.size
        obs = s.static_obstacles()
        disks = len(_disks(np.asarray(s.start, float), np.asarray(s.goal, float), obs,
                           s.robot.radius)[0]) - 2
        walls, cpus, length = [], [], float("nan")
        for _ in range(args.repeat):
            w0, c0 = time.perf_counter(), time.process_time()
            res = shortest_path(s.start, s.goal, obs, s.robot.radius, (0.0, 0.0, w, h),
                                budget=args.budget)
            walls.append(time.perf_counter() - w0)
            cpus.append(time.process_time() - c0)
            length = res.length if res.exact else float("nan")
        print(f"| {path.name} | {imported.blocked.size:,} | {t_import:.2f} | "
              f"{len(s.obstacles)} | {disks:,} | {'yes' if disks + 2 > INDEX_ABOVE else 'no'} | "
              f"{length:.4f} | {min(walls):.2f} | {min(cpus):.2f} |")
    print(f"\nload average {os.getloadavg()[0]:.1f} at the end.")


if __name__ == "__main__":
    main()
