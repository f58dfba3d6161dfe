#!/usr/bin/env python3
"""Time of the exact optimum (world.optimum.shortest_path) on imported maps.

    .venv/bin/python scripts/bench/optimum.py MAP [MAP ...] [--repeat 3] [--budget 60]
    .venv/bin/python scripts/bench/optimum.py --synthetic-warehouse [MAP ...]

MAP: a nav2 map ``.yaml`` or a MovingAI ``.map`` (1 m cells), with the importer's default start
and goal and the default robot (turtlebot3-burger, radius 0.105 m). For each map: import time,
polygons, disks (convex vertices of the union), whether the spatial index was used, the optimum
length and the best of ``--repeat`` wall times and CPU times of ``shortest_path`` (the import is
not included). Prints a markdown table and the machine's load average.

``--synthetic-warehouse`` adds a generated nav2 map of the size of navigation2's warehouse
(1006 x 1674 cells at 3 cm, 30 x 50 m): outer walls, three long rack rows and two cross racks,
a pillar grid, shelves with slots, and 300 one-cell specks of sensor noise (seed 1), written to a
temporary directory; nothing needs fetching.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from swarmpath.world.importers import load_movingai_map, load_ros_map
from swarmpath.world.optimum import INDEX_ABOVE, _disks, shortest_path


def synthetic_warehouse(directory: Path) -> Path:
    """A warehouse-size nav2 map (PGM + YAML) in ``directory``; returns the YAML path."""
    from PIL import Image

    rows, cols = 1674, 1006
    img = np.full((rows, cols), 254, dtype=np.uint8)
    img[:4, :] = img[-4:, :] = img[:, :4] = img[:, -4:] = 0  # outer walls
    for c0 in (150, 450, 750):  # long racks with a gap in the middle
        img[300:800, c0:c0 + 60] = 0
        img[880:1400, c0:c0 + 60] = 0
    img[150:190, 100:900] = 0  # cross racks
    img[1500:1540, 200:1000 - 4] = 0
    for r in range(250, 1650, 200):  # pillars
        for c in range(80, 1000, 300):
            img[r:r + 12, c:c + 12] = 0
    for c0 in range(20, 120, 10):  # a shelf of slots along the left wall
        img[1000:1100, c0:c0 + 4] = 0
    rng = np.random.default_rng(1)
    specks = rng.integers([5, 5], [rows - 5, cols - 5], size=(300, 2))
    img[specks[:, 0], specks[:, 1]] = 0
    Image.fromarray(img).save(directory / "synthetic_warehouse.pgm")
    path = directory / "synthetic_warehouse.yaml"
    path.write_text("image: synthetic_warehouse.pgm\nresolution: 0.03\norigin: [0, 0, 0]\n"
                    "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n")
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("maps", nargs="*", type=Path)
    parser.add_argument("--synthetic-warehouse", action="store_true",
                        help="add the generated warehouse-size map")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--budget", type=float, default=60.0, help="seconds per optimum")
    args = parser.parse_args()
    tmp = tempfile.TemporaryDirectory(prefix="swarmpath-bench-")
    if args.synthetic_warehouse:
        args.maps.append(synthetic_warehouse(Path(tmp.name)))
    if not args.maps:
        parser.error("give MAP files or --synthetic-warehouse")
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
