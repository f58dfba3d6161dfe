#!/usr/bin/env python3
"""Compiled clearance and sensing against the numpy reference, per map size (issue 23 section 2).

    .venv/bin/python scripts/bench/large_maps.py [--maps tests/data/random-32-32-20.map,...]
        [--rows 400] [--scans 100]

For each MovingAI map (default: random-32-32-20, arena 49 x 49, Berlin_1_256, maze512-32-9;
each cell 1 m, TurtleBot3 Burger), the exact optimum from the importer's default start to its
goal is walked in steps of the robot's speed x time step (as a run's trajectory is), and the
simulator's three geometry calls are timed with ``backend="numpy"`` and ``"numba"`` side by side
in this process, on the same inputs: the swept clearance of ``--rows`` trajectory rows
(``metrics.step_clearances``, every run's outcome), ``--scans`` sensor scans of the ICOOT paper's
80 rays (``sensors.read_sensors_in``, every decision) and as many motion-guard segments
(``clearance.segment_clearance``). CPU milliseconds per call (the best of 3 repetitions) and the
ratio, and whether the two backends gave the same doubles (they must). The kernels are loaded
before the clock starts.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "tests" / "data"
DEFAULT = ",".join(str(DATA / m) for m in (
    "random-32-32-20.map", "arena.map", "Berlin_1_256.map", "maze512-32-9.map"))


def _cpu(fn, repeat: int = 3) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeat):
        t = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--maps", default=DEFAULT)
    ap.add_argument("--rows", type=int, default=400)
    ap.add_argument("--scans", type=int, default=100)
    a = ap.parse_args()
    from swarmpath import metrics
    from swarmpath.planners.sensed_map import along
    from swarmpath.robot.sensors import get_sensor_model, read_sensors_in
    from swarmpath.world import clearance
    from swarmpath.world.importers import load_movingai_map
    from swarmpath.world.optimum import shortest_path

    model = get_sensor_model("icoot-80")
    print("| map | cells | polygons | call | numpy ms | numba ms | ratio | same doubles |")
    print("| --- | --- | --- | --- | ---: | ---: | ---: | --- |")
    for path in a.maps.split(","):
        sc = load_movingai_map(path).scenario
        static = sc.static_obstacles()
        w, h = sc.size
        best = shortest_path(sc.start, sc.goal, static, sc.robot.radius, world=(0.0, 0.0, w, h),
                             budget=None)
        step = sc.robot.linear_speed * sc.time_step
        length = float(np.sum(np.hypot(*np.diff(best.points, axis=0).T)))
        xy = along(best.points, np.minimum(np.arange(a.rows) * step, length))
        traj = np.column_stack([xy, np.arange(a.rows) * sc.time_step])
        picks = np.linspace(0, a.rows - 2, a.scans).astype(int)

        def obstacles_at(_t: float, s=static):
            return s

        def rows(backend: str, t=traj, f=obstacles_at):
            return metrics.step_clearances(t, f, backend)

        def scans(backend: str, xy=xy, picks=picks, s=static, r=sc.robot.radius):
            return [read_sensors_in(model, float(xy[i, 0]), float(xy[i, 1]), 0.0, r, s,
                                    backend=backend).distances for i in picks]

        def segments(backend: str, xy=xy, picks=picks, s=static):
            return [clearance.segment_clearance(s, xy[i], xy[i + 1] + 0.3, backend)
                    for i in picks]

        label = f"{Path(path).name} ({w:g} x {h:g} m)"
        for name, fn, per in (("step_clearances", rows, a.rows),
                              ("read_sensors_in", scans, a.scans),
                              ("segment_clearance", segments, a.scans)):
            fn("numba")  # load the kernels and the polygon index
            t_np, out_np = _cpu(lambda fn=fn: fn("numpy"))
            t_nb, out_nb = _cpu(lambda fn=fn: fn("numba"))
            same = all(np.array_equal(np.asarray(x), np.asarray(y), equal_nan=True)
                       for x, y in zip(np.atleast_1d(out_np), np.atleast_1d(out_nb),
                                       strict=True)) if isinstance(out_np, list) else \
                np.array_equal(out_np, out_nb, equal_nan=True)
            unit = "per 1,000 rows" if name == "step_clearances" else "per call"
            scale = 1000.0 / per if name == "step_clearances" else 1.0 / per
            print(f"| {label} | {int(w * h):,} | {len(static.polygons)} | {name} ({unit}) | "
                  f"{1000 * t_np * scale:.2f} | {1000 * t_nb * scale:.3f} | "
                  f"{t_np / max(t_nb, 1e-9):.0f}x | {'yes' if same else 'NO'} |", flush=True)


if __name__ == "__main__":
    main()
