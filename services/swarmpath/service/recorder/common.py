"""Where a job's MCAP files live, and the small encoding helpers the writer and the scene
drawing share (log times, topic names, finite JSON)."""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import Any

_BIG = 1.7976931348623157e308


COMPRESSION_ENV = "SWARMPATH_MCAP_COMPRESSION"
COMPRESSIONS = ("lz4", "zstd", "none")  # MCAP chunk compression names; the first is the default


def chunk_compression(value: str | None = None) -> Any:
    """The MCAP chunk compression named by ``value`` (or by ``$SWARMPATH_MCAP_COMPRESSION``;
    unset: lz4) as the writer's ``CompressionType``. lz4 is the default because it costs a
    fraction of zstd's CPU (the recorder must keep up with the farm); zstd files are about 40%
    smaller (docs/benchmarks.md). Foxglove reads both. An unknown name raises ValueError
    naming the setting."""
    from mcap.writer import CompressionType

    name = (os.environ.get(COMPRESSION_ENV, "") if value is None else value).strip().lower()
    name = name or COMPRESSIONS[0]
    if name not in COMPRESSIONS:
        raise ValueError(f"{COMPRESSION_ENV}={name!r}: the MCAP chunk compression must be one "
                         f"of {', '.join(COMPRESSIONS)}")
    return CompressionType[name.upper()]


# ------------------------------------------------------------------------------------ helpers
def no_room(exc: BaseException) -> bool:
    """Whether a write failed for want of disk space (ENOSPC, EDQUOT; also as the text of an
    error passed on from the recorder process)."""
    import errno

    if isinstance(exc, OSError) and exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return True
    return "No space left on device" in str(exc) or "Disk quota exceeded" in str(exc)


MCAP_MAGIC = b"\x89MCAP0\r\n"


def intact(path: Path) -> bool:
    """Whether a finished MCAP is whole: the magic at both ends, and a footer whose summary
    section reads with statistics (a file truncated anywhere lacks one of them). Cheap: the
    reader seeks to the footer and reads the summary only."""
    from mcap.reader import SeekingReader

    try:
        with open(path, "rb") as f:
            head = f.read(len(MCAP_MAGIC))
            f.seek(-len(MCAP_MAGIC), os.SEEK_END)
            if head != MCAP_MAGIC or f.read() != MCAP_MAGIC:
                return False
            f.seek(0)
            summary = SeekingReader(f, validate_crcs=False).get_summary()
    except Exception:  # any way of being unreadable
        return False
    return summary is not None and summary.statistics is not None


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


_SCALARS = (bool, str, int)  # (a tuple: isinstance checks it faster than a union type)


def _finite_scalar(v: Any) -> bool:
    if isinstance(v, _SCALARS):
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
