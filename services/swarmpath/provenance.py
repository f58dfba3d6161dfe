"""The numeric platform a process computes on, and a short fingerprint of it.

numpy picks some float64 loops by CPU at run time (SIMD dispatch: cbrt, exp, power, sin/cos via
SVML on AVX-512) and OpenBLAS picks its matmul kernels by CPU, so the same spec and seed can
differ in the last bit between two machines, and one last bit changes the rest of a run. Run r
is reproducible among processes with the same platform; ``numeric_platform()`` names it so a
result can say where it came from (docs/algorithms.md, "Numbers across machines").

``clean_platform`` bounds a platform dict that came from elsewhere (a worker on the bus): it is
only ever displayed and recorded, never trusted for anything else.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

import numpy as np

MAX_KEYS = 8
MAX_KEY_CHARS = 32
MAX_VALUE_CHARS = 256
FINGERPRINT_CHARS = 12


def _umath() -> Any:
    try:
        from numpy._core import _multiarray_umath as umath  # numpy >= 2
    except ImportError:  # pragma: no cover - numpy 1.26
        from numpy.core import _multiarray_umath as umath  # type: ignore[no-redef]
    return umath


def _blas() -> tuple[str, str]:
    try:
        config = np.show_config(mode="dicts")
        blas = config["Build Dependencies"]["blas"]
    except Exception:  # pragma: no cover - a numpy without build information
        return "unknown", ""
    name = f"{blas.get('name', 'unknown')} {blas.get('version', '')}".strip()
    return name, str(blas.get("openblas configuration", ""))


def fingerprint(platform: dict[str, str]) -> str:
    """A short stable hash of a platform's fields (``fingerprint`` itself excluded)."""
    body = {k: v for k, v in sorted(platform.items()) if k != "fingerprint"}
    digest = hashlib.sha256(json.dumps(body, sort_keys=True).encode()).hexdigest()
    return digest[:FINGERPRINT_CHARS]


def numeric_platform() -> dict[str, str]:
    """numpy's version, its enabled SIMD dispatch targets and baseline, its BLAS, a fingerprint.

    ``simd`` lists the dispatch targets this CPU enables (those numpy may pick at run time);
    ``blas_config`` is OpenBLAS's build line (with DYNAMIC_ARCH it picks its core at run time,
    which OPENBLAS_CORETYPE pins)."""
    umath = _umath()
    features = umath.__cpu_features__
    simd = [t for t in umath.__cpu_dispatch__ if features.get(t, False)]
    blas, blas_config = _blas()
    platform = {
        "numpy": np.__version__,
        "simd": " ".join(simd),
        "baseline": " ".join(umath.__cpu_baseline__),
        "blas": blas,
        "blas_config": blas_config,
    }
    platform = {k: v[:MAX_VALUE_CHARS] for k, v in platform.items()}
    platform["fingerprint"] = fingerprint(platform)
    return platform


def clean_platform(value: Any, field: str = "platform") -> dict[str, str]:
    """A platform dict from an untrusted sender, bounded: at most MAX_KEYS string keys of at most
    MAX_KEY_CHARS and string values of at most MAX_VALUE_CHARS. Raises ValueError naming the
    field (and key) otherwise."""
    if not isinstance(value, dict):
        raise ValueError(f"{field}: must be an object of strings")
    if len(value) > MAX_KEYS:
        raise ValueError(f"{field}: at most {MAX_KEYS} keys, got {len(value)}")
    out: dict[str, str] = {}
    for key, item in value.items():
        if not isinstance(key, str) or not key or len(key) > MAX_KEY_CHARS:
            raise ValueError(f"{field}: keys are strings of 1 to {MAX_KEY_CHARS} characters")
        if not isinstance(item, str) or len(item) > MAX_VALUE_CHARS:
            raise ValueError(
                f"{field}.{key}: must be a string of at most {MAX_VALUE_CHARS} characters")
        out[key] = item
    return out
