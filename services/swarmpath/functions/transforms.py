"""Function transforms: where the optimum sits and how the axes are turned, per run.

The registry of transform names is ``TRANSFORMS`` (the single source for the CLI, the API and
the job spec). For run r of a study with seed s:

* ``"none"``: the function as defined (optima at the origin for F1-F4, F7, F9-F11).
* ``"shift"``: the optimum moved uniformly inside the central 80% of the box, drawn from the
  run's ``SHIFT`` stream (the same for every algorithm of the study).
* ``"rotate"``: the function turned about its optimum by a random orthogonal matrix Q drawn
  from the run's own ``ROTATE`` stream (Haar measure, as COCO/BBOB draws its rotations:
  Hansen et al., "Real-parameter black-box optimization benchmarking 2009: noiseless functions
  definitions", INRIA RR-6829), i.e. f(x* + Q (x - x*)).
* ``"shift+rotate"``: both; the shift is the one of ``"shift"``, the rotation that of
  ``"rotate"``, so the transforms of a run differ only by what they add.

What rotation means here:

* Separable functions (F1, F6, F8, F9, and the penalty terms of F12 and F13) become
  non-separable: a coordinate-wise search no longer decomposes them. F1 and F6 are spheres about
  their optimum and do not change at all (a rotation about the centre of a sphere leaves its
  values unchanged); F4 (max |x_i|) becomes the norm of a rotated cube. Non-separable functions
  (F2-F5, F7, F10, F11) change shape too; Ackley's F10 is nearly rotation invariant (its
  first term is a sphere).
* The box does not rotate. Inside it, the rotated function is evaluated at x* + Q (x - x*),
  which can lie outside the kernel's box by up to (sqrt(d) - 1) half-widths in the corners. The
  kernels of F1-F7 and F9-F13 are defined everywhere (F12 and F13 penalise such points through
  u(x, a, k, m)); F8 is unbounded below outside its box and is wrapped back into it, as for the
  shift. The minimum value f_min is unchanged in every case, and the minimiser stays where it
  was (at x*, or at x* + shift), inside the box.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

TRANSFORMS: tuple[str, ...] = ("none", "shift", "rotate", "shift+rotate")


def check_transform(name: str) -> str:
    """The transform's name, or ValueError naming the valid ones."""
    if name not in TRANSFORMS:
        raise ValueError(f"transform must be one of {', '.join(TRANSFORMS)}, got {name!r}")
    return name


def shifts(name: str) -> bool:
    return "shift" in check_transform(name)


def rotates(name: str) -> bool:
    return "rotate" in check_transform(name)


def random_rotation(dim: int, rng: np.random.Generator) -> Array:
    """A Haar-distributed orthogonal matrix (dim, dim): QR of a standard normal matrix with the
    signs of R's diagonal moved into Q (Mezzadri, Notices AMS 54(5), 2007)."""
    q, r = np.linalg.qr(rng.standard_normal((dim, dim)))
    signs = np.sign(np.diag(r))
    signs[signs == 0] = 1.0
    return np.ascontiguousarray(q * signs)
