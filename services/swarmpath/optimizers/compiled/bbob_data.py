"""The ``data`` array of a compiled BBOB objective: an instance's constants (x_opt, f_opt,
rotations, the constant vectors numpy computes once per call), computed by the same numpy
expressions as the numpy suite (:mod:`swarmpath.functions.suites.bbob`); the layout the
compiled functions of :mod:`.bbob` read (d the dimension)::

    [0] length  [1] f_opt  [2:8] scalars  [8:8+d] x_opt  then A (d, d), B (d, d),
    c1, c2, c3 (d each), then the function's extra constants
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from swarmpath.functions.suites import bbob
from swarmpath.functions.suites.bbob_parts import conditioning

#: entries before x_opt: the length, f_opt and six scalars
HEADER = 8


def _ramp(dim: int) -> np.ndarray:
    return np.arange(dim) / (dim - 1.0)


def pack(fid: int, dim: int, instance: int) -> np.ndarray:
    """The ``data`` array of f``fid`` on ``instance`` in ``dim`` dimensions."""
    d = bbob.instance_data(fid, dim, instance)
    zeros = np.zeros(dim)
    scalars = np.zeros(6)
    xopt = np.asarray(d["xopt"], dtype=float)
    A = np.zeros((dim, dim))
    B = np.zeros((dim, dim))
    c1: np.ndarray = zeros
    c2: np.ndarray = zeros
    c3: np.ndarray = zeros
    extra: list[np.ndarray] = []
    if fid == 2:
        c1 = 1e6 ** _ramp(dim)
    elif fid in (3, 20):
        c1 = conditioning(dim, 10.0)
        c2 = 0.2 * _ramp(dim)
        if fid == 20:
            c1, c2, c3 = 2.0 * d["signs"], 2.0 * np.abs(d["xopt"]), conditioning(dim, 10.0)
    elif fid == 4:
        c1 = 10.0 ** (0.5 * np.arange(dim) / (dim - 1.0))
    elif fid == 5:
        c1 = np.sign(d["xopt"]) * math.sqrt(100.0) ** _ramp(dim)
        c2 = 5.0 * np.abs(c1)
    elif fid in (6, 9, 13, 19, 23):
        A = d["m"]
        if fid == 23:
            scalars[:2] = 10.0 / dim / dim, 10.0 / dim ** 1.2
            extra.append(2.0 ** np.arange(1, 33))
    elif fid == 7:
        c = np.sqrt((100.0 / 10.0) ** _ramp(dim))
        A, B, c1 = c[:, None] * d["r2"], d["r1"], 100.0 ** _ramp(dim)
    elif fid == 8:
        scalars[0] = max(1.0, math.sqrt(dim) / 8.0)
    elif fid in (10, 11, 12, 14):
        A = d["r1"]
        c1 = {10: 1e6 ** _ramp(dim), 11: zeros, 12: 0.5 * _ramp(dim),
              14: 2.0 + 4.0 * np.arange(dim) / (dim - 1)}[fid]
    elif fid in (15, 16):
        A, B, c1 = d["r1"], d["m"], 0.2 * _ramp(dim)
        if fid == 16:
            scalars[0] = bbob._W_F0
            extra += [bbob._W_A, bbob._W_B]
    elif fid in (17, 18):
        condition = 10.0 if fid == 17 else 1000.0
        A, B = d["r1"], d["r2"]
        c1, c2 = 0.5 * _ramp(dim), math.sqrt(condition) ** _ramp(dim)
    elif fid in (21, 22):
        A = d["r"]
        scalars[0] = len(d["heights"])
        extra += [d["local"].ravel(), d["scales"].ravel(), d["heights"]]
    elif fid == 24:
        s = 1.0 - 0.5 / (math.sqrt(dim + 20.0) - 4.1)
        scalars[:2] = s, -math.sqrt((2.5 * 2.5 - 1.0) / s)
        A, B = conditioning(dim, 100.0)[:, None] * d["r2"], d["r1"]
        c1 = np.where(d["xopt"] < 0.0, -1.0, 1.0)
    parts = [np.array([0.0, float(d["fopt"])]), scalars, xopt, A.ravel(), B.ravel(),
             np.broadcast_to(c1, (dim,)), np.broadcast_to(c2, (dim,)),
             np.broadcast_to(c3, (dim,)), *extra]
    out = np.ascontiguousarray(np.concatenate(parts), dtype=np.float64)
    out[0] = out.size
    return out


def data_for(fn: Any, dim: int) -> np.ndarray:
    """:func:`pack` for a registered ``bbob:f<k>[@i<n>]`` function."""
    return pack(int(fn.number), int(dim), int(fn.instance))
