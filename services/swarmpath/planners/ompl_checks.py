"""Exact clearance tests of the OMPL baselines in plain Python (:class:`FastChecker`).

OMPL calls its state and motion validators once per state or edge, where numpy's per-call
overhead dominates; :mod:`swarmpath.planners.ompl_baselines` uses these instead (same formulas as
:class:`~swarmpath.world.geometry.ObstacleSet`).
"""

from __future__ import annotations

from swarmpath.world.geometry import ObstacleSet


def _seg_point_d2(px: float, py: float, ax: float, ay: float, dx: float, dy: float,
                  dd: float) -> float:
    """Squared distance from P to segment A + t (dx, dy), t in [0, 1]; dd = dx^2 + dy^2."""
    if dd > 0.0:
        t = ((px - ax) * dx + (py - ay) * dy) / dd
        t = 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
    else:
        t = 0.0
    ex = ax + t * dx - px
    ey = ay + t * dy - py
    return ex * ex + ey * ey


def _orient(ax: float, ay: float, bx: float, by: float, cx: float, cy: float) -> float:
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


class FastChecker:
    """Clearance tests ``> threshold`` against a static map, in plain Python (OMPL calls these
    once per state or edge, where numpy's per-call overhead dominates).

    Circles: centre distance against ``R + threshold``. Polygons: even-odd inside test and edge
    distances, only for polygons whose bounding box lies within ``threshold`` of the query's.
    """

    def __init__(self, obstacles: ObstacleSet, threshold: float):
        self.threshold = float(threshold)
        thr = self.threshold
        self.circles = [
            (float(cx), float(cy), float(r) + thr, (float(r) + thr) ** 2)
            for cx, cy, r in obstacles.circles
        ]
        self.polygons: list[tuple[float, float, float, float, list[tuple[float, ...]]]] = []
        for poly in obstacles.polygons:
            pts = [(float(x), float(y)) for x, y in poly]
            edges: list[tuple[float, ...]] = []
            for i, (ax, ay) in enumerate(pts):
                bx, by = pts[(i + 1) % len(pts)]
                dx, dy = bx - ax, by - ay
                edges.append((ax, ay, bx, by, dx, dy, dx * dx + dy * dy))
            xs = [p[0] for p in pts]
            ys = [p[1] for p in pts]
            self.polygons.append((min(xs) - thr, min(ys) - thr, max(xs) + thr, max(ys) + thr,
                                  edges))

    @staticmethod
    def _inside(px: float, py: float, edges: list[tuple[float, ...]]) -> bool:
        inside = False
        for ax, ay, bx, by, *_ in edges:
            if (ay > py) != (by > py) and px < ax + (py - ay) * (bx - ax) / (by - ay):
                inside = not inside
        return inside

    def point_ok(self, px: float, py: float) -> bool:
        for cx, cy, _, rr in self.circles:
            ex, ey = px - cx, py - cy
            if ex * ex + ey * ey <= rr:
                return False
        t2 = self.threshold * self.threshold
        for x0, y0, x1, y1, edges in self.polygons:
            if px < x0 or px > x1 or py < y0 or py > y1:
                continue
            if self._inside(px, py, edges):
                return False
            for ax, ay, _bx, _by, dx, dy, dd in edges:
                if _seg_point_d2(px, py, ax, ay, dx, dy, dd) <= t2:
                    return False
        return True

    def segment_ok(self, ax: float, ay: float, bx: float, by: float) -> bool:
        dx, dy = bx - ax, by - ay
        dd = dx * dx + dy * dy
        for cx, cy, _, rr in self.circles:
            if _seg_point_d2(cx, cy, ax, ay, dx, dy, dd) <= rr:
                return False
        if not self.polygons:
            return True
        t2 = self.threshold * self.threshold
        lx, hx = (ax, bx) if ax <= bx else (bx, ax)
        ly, hy = (ay, by) if ay <= by else (by, ay)
        for x0, y0, x1, y1, edges in self.polygons:
            if hx < x0 or lx > x1 or hy < y0 or ly > y1:
                continue
            if self._inside(ax, ay, edges):
                return False
            for cx, cy, ex, ey, fx, fy, ff in edges:
                # proper crossing -> distance 0; otherwise the closest pair involves an endpoint
                o1 = _orient(ax, ay, bx, by, cx, cy)
                o2 = _orient(ax, ay, bx, by, ex, ey)
                o3 = _orient(cx, cy, ex, ey, ax, ay)
                o4 = _orient(cx, cy, ex, ey, bx, by)
                if o1 * o2 < 0.0 and o3 * o4 < 0.0:
                    return False
                if (_seg_point_d2(ax, ay, cx, cy, fx, fy, ff) <= t2
                        or _seg_point_d2(bx, by, cx, cy, fx, fy, ff) <= t2
                        or _seg_point_d2(cx, cy, ax, ay, dx, dy, dd) <= t2
                        or _seg_point_d2(ex, ey, ax, ay, dx, dy, dd) <= t2):
                    return False
        return True
