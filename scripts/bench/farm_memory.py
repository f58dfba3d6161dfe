"""The coordinator's memory over a farm job (used by scripts/bench/farm.py).

:func:`proc_memory` reads a process's resident memory from /proc and splits it: anonymous
(heaps: Python objects, the allocator's arenas, Zenoh's link buffers, SQLite's page cache) and
file-backed (the mapped libraries and files). :func:`memory_profile` turns the samples taken
while a job runs - (seconds, runs finished, RSS, anonymous, file-backed) - into what tells
whether the memory is flat: the RSS when the job was submitted and when 25, 50, 75 and 100 %
of its runs were finished, and the slope of the RSS over the second half of the job, per run
and per second (least squares over the samples from 50 % to 100 %).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

QUARTERS = (25, 50, 75, 100)


def proc_memory(pid: int) -> tuple[float, float, float]:
    """(RSS, anonymous, file-backed) resident MB of process ``pid`` (/proc/PID/status)."""
    kib = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        name, _, value = line.partition(":")
        if name in ("VmRSS", "RssAnon", "RssFile", "RssShmem"):
            kib[name] = int(value.split()[0])
    return (kib["VmRSS"] / 1024, kib["RssAnon"] / 1024,
            (kib["RssFile"] + kib.get("RssShmem", 0)) / 1024)


def _slope(xs: Sequence[float], ys: Sequence[float]) -> float | None:
    """Least-squares slope of ys over xs; None when the xs do not vary."""
    n = len(xs)
    if n < 2:
        return None
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    if sxx == 0:
        return None
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sxx


def memory_profile(samples: Sequence[tuple[float, int, float, float, float]],
                   total_runs: int) -> dict[str, Any]:
    """What the samples (seconds, runs finished, RSS MB, anonymous MB, file MB), in time order,
    say about the memory over one job of ``total_runs`` runs.

    ``rss_at`` / ``anon_at``: MB at the first sample (submission, key "0") and at the first
    sample where at least q % of the runs were finished (q = 25, 50, 75, 100; missing when the
    job never got there). ``second_half_mb``: RSS at 100 % minus RSS at 50 %.
    ``slope_kb_per_run`` and ``slope_mb_per_s``: least-squares slopes of the RSS over the
    samples from the 50 % one to the 100 % one (None with fewer than two)."""
    if not samples or total_runs < 1:
        return {"rss_at": {}, "anon_at": {}, "second_half_mb": None,
                "slope_kb_per_run": None, "slope_mb_per_s": None}
    first: dict[str, int] = {"0": 0}
    for q in QUARTERS:
        for i, (_t, runs, *_rest) in enumerate(samples):
            if runs * 100 >= q * total_runs:
                first[str(q)] = i
                break
    rss_at = {k: round(samples[i][2], 1) for k, i in first.items()}
    anon_at = {k: round(samples[i][3], 1) for k, i in first.items()}
    out: dict[str, Any] = {"rss_at": rss_at, "anon_at": anon_at, "second_half_mb": None,
                           "slope_kb_per_run": None, "slope_mb_per_s": None}
    if "50" in first and "100" in first:
        half = samples[first["50"]: first["100"] + 1]
        out["second_half_mb"] = round(rss_at["100"] - rss_at["50"], 1)
        per_run = _slope([s[1] for s in half], [s[2] * 1024 for s in half])
        per_s = _slope([s[0] for s in half], [s[2] for s in half])
        out["slope_kb_per_run"] = None if per_run is None else round(per_run, 3)
        out["slope_mb_per_s"] = None if per_s is None else round(per_s, 4)
    return out


def profile_line(profile: dict[str, Any]) -> str:
    """One markdown-friendly line: RSS at 0/25/50/75/100 % of the job and the second half's
    slope."""
    at = profile["rss_at"]
    marks = ", ".join(f"{k} % {at[k]}" for k in ("0", *map(str, QUARTERS)) if k in at)
    anon = profile["anon_at"]
    anon_marks = " / ".join(str(anon[k]) for k in ("0", *map(str, QUARTERS)) if k in anon)
    return (f"RSS MB at {marks} of the runs (anonymous {anon_marks}); second half "
            f"{profile['second_half_mb']} MB, slope {profile['slope_kb_per_run']} KB per run, "
            f"{profile['slope_mb_per_s']} MB/s")
