"""Virtual range sensors: the only way a local planner sees the world.

A sensor model is a fan of rays around the robot grouped into sensors. Each ray returns the
distance from the robot *body* (its circular footprint) to the first obstacle surface along it, or
+inf beyond the sensor's range. A sensor fires when any of its rays hits within range.

Models (registry :data:`SENSOR_MODELS`):

* ``mfb-12`` — Ajeil et al. 2020: 12 sensors 30 degrees apart, each covering its 30-degree sector,
  sensing range SR = 0.8 m. The sensory vector Vs (12 bits) and the gap vector
  Vg_i = Vs_i OR Vs_{i+1} (eq 24, cyclic) are derived from the readings. The paper measures the
  range from the robot; we measure it from the body surface (sensors sit on the perimeter), which
  matters for the 0.5 m robot of the static map.
* ``icoot-80`` — Abdulsaheb & Kadhim 2022, section 4.2: 80 virtual sensors in four layers of 8, 16,
  24 and 32, each sensor covering 360/n degrees of its layer. The paper gives no layer ranges; layer
  k (1..4) reaches k/4 of ``range`` (default 2 m) from the body, so near obstacles are seen at fine
  angular resolution by every layer and far ones by the outer, denser layers.

Sectors are sampled with a few rays each (``rays_per_sensor``); an obstacle thinner than the gap
between rays at that distance can be missed, which the simulator's exact collision check then
reports: results are checked, never trusted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmpath.world import clearance
from swarmpath.world.geometry import ObstacleSet

Array = NDArray[np.float64]


@dataclass(frozen=True)
class SensorModel:
    name: str
    angles: Array  # (n_rays,) body-frame ray angles, radians
    ranges: Array  # (n_rays,) max range from the body surface, metres
    sensor_of_ray: NDArray[np.int64]  # (n_rays,) index of the sensor each ray belongs to
    n_sensors: int
    description: str = ""


@dataclass(frozen=True)
class SensorReading:
    distances: Array  # (n_rays,) from the body surface; inf if nothing within range
    hit_points: Array  # (h, 2) world coordinates of the hits within range
    fired: NDArray[np.bool_]  # (n_sensors,) the sensory vector Vs
    nearest: Array  # (n_sensors,) nearest hit per sensor (inf if none)

    def gap_vector(self) -> NDArray[np.bool_]:
        """Eq 24 of Ajeil et al.: Vg_i = Vs_i OR Vs_{i+1}, cyclic."""
        return self.fired | np.roll(self.fired, -1)


def _fan(n_sensors: int, rng: float, rays_per_sensor: int, offset: float = 0.0) -> tuple[
    Array, Array, NDArray[np.int64]
]:
    width = 2 * np.pi / n_sensors
    centres = offset + width * np.arange(n_sensors)
    # rays spread evenly inside each sector (not on its borders, so sectors do not share rays)
    frac = (np.arange(rays_per_sensor) + 0.5) / rays_per_sensor - 0.5
    angles = (centres[:, None] + width * frac[None, :]).ravel()
    owner = np.repeat(np.arange(n_sensors), rays_per_sensor)
    return angles, np.full(angles.shape, rng), owner


def mfb_12(sensing_range: float = 0.8, rays_per_sensor: int = 6) -> SensorModel:
    angles, ranges, owner = _fan(12, sensing_range, rays_per_sensor)
    return SensorModel("mfb-12", angles, ranges, owner, 12,
                       "12 sectors of 30 degrees, 0.8 m range (Ajeil et al. 2020)")


def icoot_80(sensing_range: float = 2.0, rays_per_sensor: int = 3) -> SensorModel:
    parts = []
    first = 0
    for k, n in enumerate((8, 16, 24, 32), start=1):
        angles, ranges, owner = _fan(n, sensing_range * k / 4, rays_per_sensor)
        parts.append((angles, ranges, owner + first))
        first += n
    return SensorModel(
        "icoot-80",
        np.concatenate([p[0] for p in parts]),
        np.concatenate([p[1] for p in parts]),
        np.concatenate([p[2] for p in parts]),
        80,
        "four layers of 8/16/24/32 sensors (Abdulsaheb & Kadhim 2022)",
    )


SENSOR_MODELS = {"mfb-12": mfb_12, "icoot-80": icoot_80}


def get_sensor_model(name: str, **kwargs: float) -> SensorModel:
    try:
        factory = SENSOR_MODELS[name]
    except KeyError:
        valid = ", ".join(SENSOR_MODELS)
        raise KeyError(f"unknown sensor model {name!r}; valid: {valid}") from None
    return factory(**kwargs)  # type: ignore[arg-type]


# ----------------------------------------------------------------------------- ray casting
def ray_circle_distance(origin: Array, dirs: Array, circles: Array) -> Array:
    """Distance along unit rays ``dirs`` (n,2) from ``origin`` (2,) to the nearest circle (k,3).

    0 if the origin is inside a circle; inf when a ray misses everything.
    """
    if len(circles) == 0:
        return np.full(len(dirs), np.inf)
    oc = origin[None, :] - circles[:, :2]  # (k, 2)
    c = np.einsum("kj,kj->k", oc, oc) - circles[:, 2] ** 2  # (k,)
    b = dirs @ oc.T  # (n, k): d . (o - c)
    disc = b * b - c[None, :]
    sq = np.sqrt(np.maximum(disc, 0.0))
    t_near = -b - sq
    t_far = -b + sq
    # origin inside: t_near < 0 < t_far
    t = np.where(t_near >= 0, t_near, np.where(t_far >= 0, 0.0, np.inf))
    t = np.where(c[None, :] <= 0, 0.0, t)
    t = np.where(disc >= 0, t, np.inf)
    return np.asarray(t.min(axis=1))


def ray_segment_distance(origin: Array, dirs: Array, A: Array, B: Array) -> Array:
    """Distance along unit rays (n,2) to the nearest of segments A(m,2)-B(m,2); inf if none."""
    if len(A) == 0:
        return np.full(len(dirs), np.inf)
    e = B - A  # (m, 2)
    w = A - origin[None, :]  # (m, 2)
    denom = dirs[:, 0:1] * e[None, :, 1] - dirs[:, 1:2] * e[None, :, 0]  # cross(d, e): (n, m)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[None, :, 0] * e[None, :, 1] - w[None, :, 1] * e[None, :, 0]) / denom
        u = (w[None, :, 0] * dirs[:, 1:2] - w[None, :, 1] * dirs[:, 0:1]) / denom
    ok = (np.abs(denom) > 1e-15) & (t >= 0) & (u >= 0) & (u <= 1)
    return np.asarray(np.where(ok, t, np.inf).min(axis=1))


def _inside_any_polygon(p: Array, polygons: tuple[Array, ...]) -> bool:
    for poly in polygons:
        x, y = poly[:, 0], poly[:, 1]
        xn, yn = np.roll(x, -1), np.roll(y, -1)
        crosses = (y > p[1]) != (yn > p[1])
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = x + (p[1] - y) * (xn - x) / (yn - y)
        if np.count_nonzero(crosses & (p[0] < xi)) % 2 == 1:
            return True
    return False


def read_sensors(
    model: SensorModel,
    x: float,
    y: float,
    theta: float,
    body_radius: float,
    circles: Array,
    polygons: tuple[Array, ...],
) -> SensorReading:
    """Cast the model's rays from the robot centre; distances are measured from the body surface."""
    origin, dirs = _rays(model, x, y, theta)
    t = ray_circle_distance(origin, dirs, np.asarray(circles, dtype=float).reshape(-1, 3))
    if polygons:
        A = np.concatenate([p for p in polygons])
        B = np.concatenate([np.roll(p, -1, axis=0) for p in polygons])
        t = np.minimum(t, ray_segment_distance(origin, dirs, A, B))
        if _inside_any_polygon(origin, polygons):
            t = np.zeros_like(t)
    return _reading(model, origin, dirs, t, body_radius)


def read_sensors_in(
    model: SensorModel,
    x: float,
    y: float,
    theta: float,
    body_radius: float,
    obstacles: ObstacleSet,
    backend: str = "auto",
) -> SensorReading:
    """:func:`read_sensors` against an obstacle set. With ``backend`` ``"numba"`` (``"auto"``:
    when numba is installed) the polygons' edges are visited only where they come within the
    longest ray's reach of the robot (:func:`swarmpath.world.clearance.polygon_rays`): a
    farther edge could only be hit beyond the range, which reads as nothing, so the reading is
    the same to the last bit."""
    if clearance.resolve(backend) == "numpy" or not obstacles.polygons:
        return read_sensors(model, x, y, theta, body_radius, obstacles.circles,
                            obstacles.polygons)
    origin, dirs = _rays(model, x, y, theta)
    t = ray_circle_distance(origin, dirs, obstacles.circles)
    reach = float(np.max(model.ranges)) + body_radius
    t_poly, inside = clearance.polygon_rays(obstacles, origin, dirs, reach)
    t = np.minimum(t, t_poly)
    if inside:
        t = np.zeros_like(t)
    return _reading(model, origin, dirs, t, body_radius)


def _rays(model: SensorModel, x: float, y: float, theta: float) -> tuple[Array, Array]:
    """The robot centre and the rays' world-frame unit directions."""
    origin = np.array([x, y], dtype=float)
    world = model.angles + theta
    return origin, np.stack([np.cos(world), np.sin(world)], axis=1)


def _reading(model: SensorModel, origin: Array, dirs: Array, t: Array,
             body_radius: float) -> SensorReading:
    """The reading of rays that first meet an obstacle at distances ``t`` from the centre."""
    from_body = np.maximum(t - body_radius, 0.0)
    within = from_body <= model.ranges
    distances = np.where(within, from_body, np.inf)
    hits = origin[None, :] + dirs[within] * t[within, None]
    nearest = np.full(model.n_sensors, np.inf)
    np.minimum.at(nearest, model.sensor_of_ray, distances)
    return SensorReading(distances, hits, np.isfinite(nearest), nearest)
