"""Where a job's MCAP files live, and the small encoding helpers the writer and the scene
drawing share (log times, topic names, finite JSON)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any

_BIG = 1.7976931348623157e308


# ------------------------------------------------------------------------------------ helpers
def mcap_dir(data_dir: Path | str) -> Path:
    return Path(data_dir) / "mcap"


def final_path(data_dir: Path | str, job_id: str) -> Path:
    return mcap_dir(data_dir) / f"{job_id}.mcap"


def part_path(data_dir: Path | str, job_id: str) -> Path:
    return mcap_dir(data_dir) / f"{job_id}.mcap.part"


def _ns(seconds: float) -> int:
    return max(0, round(seconds * 1e9))


def _topic_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"


def _finite_scalar(v: Any) -> bool:
    if isinstance(v, bool | str | int):
        return True
    return isinstance(v, float) and math.isfinite(v)


def _clamp(v: float) -> float:
    """Curve values for Foxglove's JSON parser (no Infinity/NaN): clamp to the float range."""
    if math.isfinite(v):
        return v
    return -_BIG if v < 0 else _BIG


def clamped(values: Any, as_array: bool = False) -> Any:
    """A curve as a list of finite floats (non-finite values clamped, see :func:`_clamp`), or
    as a float64 array with ``as_array``; vectorized: a 500-value curve costs microseconds,
    not a Python loop per value."""
    import numpy as np

    arr = np.asarray(values, dtype=float)
    bad = ~np.isfinite(arr)
    if bad.any():
        arr = np.where(bad, np.where(arr < 0, -_BIG, _BIG), arr)
    return arr if as_array else arr.tolist()


def _json(obj: Any) -> bytes:
    return json.dumps(obj, separators=(",", ":"), allow_nan=False).encode()


def _version() -> str:
    try:
        from swarmpath import __version__
    except ImportError:  # pragma: no cover
        return "unknown"
    return __version__
