"""Convergence curves in IOHprofiler's formats (``swarmpath results JOB --format ioh -o DIR``),
which IOHanalyzer and its Python counterpart ``iohinspector`` load.

The default is the form IOHexperimenter (0.3) writes and ``iohinspector.DataManager.add_folder``
reads: per algorithm a folder holding, per function, a meta-data file
``IOHprofiler_f<id>_<name>.json`` (``version``, ``suite``, ``function_id``, ``function_name``,
``maximization``, ``algorithm`` {name, info}, ``attributes`` ["evaluations", "raw_y"] and per
dimension a ``scenario``: its ``dimension``, the raw-data ``path`` and one entry per run:
``instance``, ``evals``, ``best`` {evals, y, x}) and the raw data
``data_f<id>_<name>/IOHprofiler_f<id>_DIM<d>.dat``: per run the header ``evaluations raw_y``, then
one line per improvement ``<evaluations> <best-so-far>``, the first at evaluation 1 (the readers
start a run where the evaluations count is 1), the last at the run's last evaluation.
``--format ioh-info`` writes the older meta-data form instead (IOHanalyzer's "Supported Data
Format" page: three lines per dimension in ``IOHprofiler_f<id>_<name>.info``, raw-data blocks
separated by ``"function evaluation" "best-so-far f(x)"``), which iohinspector does not read.

Values are the best-so-far error f - f* (COCO's .dat files record the same: the best
noise-free value minus f_opt), so F8, whose minimum is negative, and every other function read
on a log scale. swarmpath records the best-so-far after each iteration. The evaluations after
iteration k are taken as ``round(N + k * (E - N) / T)`` (N: the agents, evaluated once before the
first iteration; E: the run's evaluations; T: the iterations), exact for the algorithms that
evaluate the initial population and then the same number of agents each iteration; the value
after the first iteration is written at evaluation 1, so runtimes within the first iteration are
not resolved. A curve the service thinned (``curve_stride`` s) has iterations 1, 1 + s, 1 + 2s,
... and the last one. Runs of a transformed job (shift, rotate) are instances 1 + run (each run
moves or turns the function); otherwise every run is instance 1. Non-finite values (an
infeasible start) are left out; a run without a finite value is left out and counted.

Function ids are stable (:func:`function_id`) and unique within a suite label: a swarmpath
function F<n> is n (F8 is IOHanalyzer's f8 whatever else is registered), a variant
F<n>-<suffix> is 100 + n; a suite function is written as its suite numbers it (``suite``
"bbob", id 3 for bbob:f3, as COCO and IOHprofiler do; the function's ``number``, else the
trailing digits of its name) and the runs of all its instances go to one file, each with its
instance id; a plugin may name its own with :func:`register_function_id`; anything else gets
10000 + crc32(name) mod 90000, and two functions of one suite label on one id are refused,
naming both.
"""

from __future__ import annotations

import json
import re
import zlib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

SEPARATOR = '"function evaluation" "best-so-far f(x)"'
JSON_HEADER = "evaluations raw_y"
FORMATS = ("ioh", "ioh-info")
#: Explicit ids (name -> id), extended by plugins.
_IDS: dict[str, int] = {}
_VARIANT_BASE = 100
_FALLBACK = (10_000, 90_000)


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("_") or "x"


def register_function_id(name: str, fid: int) -> None:
    """Give function ``name`` the IOHprofiler id ``fid`` in every export (a plugin's choice)."""
    if fid < 1:
        raise ValueError(f"an IOHprofiler function id is a positive integer, got {fid}")
    _IDS[name] = int(fid)


def function_id(name: str) -> int:
    """The stable IOHprofiler id of function ``name`` (see the module doc)."""
    if name in _IDS:
        return _IDS[name]
    m = re.fullmatch(r"F(\d+)", name)
    if m:
        return int(m[1])
    m = re.fullmatch(r"F(\d+)-[A-Za-z][\w-]*", name)
    if m:
        return _VARIANT_BASE + int(m[1])
    if ":" in name:  # a suite function: its number in the suite
        number = _suite_number(name)
        if number:
            return number
    low, size = _FALLBACK
    return low + zlib.crc32(name.encode()) % size


def _suite_number(name: str) -> int:
    try:
        from swarmpath.functions import get_function

        number = int(getattr(get_function(name), "number", 0) or 0)
    except (KeyError, ValueError):
        number = 0
    m = re.search(r"(\d+)$", name)
    return number or (int(m[1]) if m else 0)


def _suite_of(name: str) -> tuple[str, str, int | None]:
    """(suite label, function name without its instance, instance) of a function name."""
    from swarmpath.functions.suites.base import split_instance

    base, instance = split_instance(name)
    suite, colon, _ = base.partition(":")
    if not colon:
        return "swarmpath", name, None
    return suite, base, 1 if instance is None else instance


def _suite(name: str) -> str:
    return _suite_of(name)[0]


def evaluation_points(length: int, iterations: int, evaluations: int, stride: int = 1,
                      initial: int = 0) -> list[int]:
    """Evaluations spent after each stored curve sample (see the module doc): ``initial`` for
    the first population, then an equal share of the rest per iteration (strictly increasing)."""
    if length == 0:
        return []
    iterations = max(iterations, length)
    its = np.minimum(np.arange(length) * stride, iterations - 1) + 1
    its[-1] = iterations
    initial = min(max(initial, 0), evaluations)
    per = (evaluations - initial) / iterations
    e = np.maximum(1, np.rint(initial + its * per)).astype(np.int64)
    k = np.arange(length)
    out: list[int] = (np.maximum.accumulate(e - k) + k).tolist()
    return out


def run_block(curve: list[float], points: list[int]) -> list[tuple[int, float]]:
    """The (evaluations, best-so-far) lines of one run: the first finite value, each
    improvement, and the last evaluation."""
    c = np.asarray(curve, dtype=float)
    finite = np.isfinite(c)
    if not finite.any():
        return []
    cf = np.where(finite, c, np.inf)
    before = np.concatenate([[np.inf], np.minimum.accumulate(cf)[:-1]])
    keep = np.flatnonzero(finite & (cf < before))
    lines = [(int(points[i]), float(c[i])) for i in keep]
    if lines[-1][0] != points[-1]:
        lines.append((int(points[-1]), lines[-1][1]))
    return lines


@dataclass
class Written:
    files: list[Path] = field(default_factory=list)
    runs: int = 0
    skipped: int = 0  # finished runs without a finite value or a curve


def _num(v: float) -> str:
    return f"{v:.10e}"


def _check_ids(functions: Iterable[str]) -> None:
    seen: dict[tuple[str, int], str] = {}
    for name in functions:
        key = (_suite(name), function_id(name))
        if key in seen and seen[key] != name:
            raise ValueError(f"functions {seen[key]!r} and {name!r} both have IOHprofiler id "
                             f"{key[1]}: give one another with register_function_id")
        seen[key] = name


def write_ioh(items: Iterable[Mapping[str, Any]], directory: Path, job_id: str = "",
              fmt: str = "ioh") -> Written:
    """Write every finished benchmark run's curve under ``directory`` in ``fmt`` (``ioh``: the
    JSON meta-data form; ``ioh-info``: the older .info form; see the module doc)."""
    if fmt not in FORMATS:
        raise ValueError(f"format {fmt!r} is not one of {', '.join(FORMATS)}")
    from swarmpath import __version__
    from swarmpath.evidence.benchmark_stats import f_star

    groups: dict[tuple[str, str, int], list[Mapping[str, Any]]] = {}
    out = Written()
    for item in items:
        if item.get("state") != "done" or "algorithm" not in item:
            continue
        if not item.get("curve"):
            out.skipped += 1
            continue
        # a suite function's instances are runs of one function (instance ids in the meta-data)
        groups.setdefault((str(item["algorithm"]), _suite_of(str(item["function"]))[1],
                           int(item["dim"])), []).append(item)
    _check_ids({f for _, f, _ in groups})
    metas: dict[Path, dict[str, Any]] = {}
    infos: dict[Path, list[str]] = {}
    order = sorted(groups.items(), key=lambda kv: (kv[0][0], function_id(kv[0][1]), kv[0][2]))
    for (algorithm, function, dim), runs in order:
        fid = function_id(function)
        name = _slug(function)
        folder = directory / _slug(algorithm)
        rel = f"data_f{fid}_{name}/IOHprofiler_f{fid}_DIM{dim}.dat"
        dat_path = folder / rel
        fs = f_star(function, dim) if ":" not in function else 0.0  # suites: already errors
        entries: list[dict[str, Any]] = []
        lines: list[str] = []
        spec: Mapping[str, Any] = {}
        for item in sorted(runs, key=lambda r: (_suite_of(str(r["function"]))[2] or 0,
                                                int(r["run"]))):
            spec = item.get("spec") or {}
            curve = [float(v) - fs for v in item["curve"]]
            iterations = int(spec.get("iterations") or len(curve))
            evaluations = int(item.get("evaluations") or iterations)
            stride = int(item.get("curve_stride") or 1)
            points = evaluation_points(len(curve), iterations, evaluations, stride,
                                       int(spec.get("agents") or 0))
            block = run_block(curve, points)
            if not block:
                out.skipped += 1
                continue
            instance = _suite_of(str(item["function"]))[2] or (
                int(item["run"]) + 1 if _transform(spec) != "none" else 1)
            if fmt == "ioh":
                if block[0][0] != 1:  # readers start a run at evaluation 1
                    block = [(1, block[0][1]), *block[1:]] + (block[-1:] if len(block) == 1
                                                                else [])
                lines.append(JSON_HEADER)
            else:
                lines.append(SEPARATOR)
            lines += [f"{e} {_num(v)}" for e, v in block]
            best_at = next(e for e, v in block if v == block[-1][1])
            entries.append({"instance": instance, "evals": block[-1][0],
                            "best": {"evals": best_at, "y": block[-1][1],
                                     "x": [float(v) for v in item.get("best_position") or []]}})
            out.runs += 1
        if not entries:
            continue
        dat_path.parent.mkdir(parents=True, exist_ok=True)
        dat_path.write_text("\n".join(lines) + "\n", encoding="ascii")
        out.files.append(dat_path)
        # no commas inside values: the .info form splits its first line at commas
        alg_info = (f"{spec.get('agents', '?')} agents; {spec.get('iterations', '?')} "
                    f"iterations; seed {runs[0].get('seed', '?')}"
                    + (f"; transform {_transform(spec)}" if _transform(spec) != "none" else "")
                    + "; values f - f*" + (f"; swarmpath job {job_id}" if job_id else ""))
        if fmt == "ioh":
            meta = metas.setdefault(folder / f"IOHprofiler_f{fid}_{name}.json", {
                "version": f"swarmpath {__version__}", "suite": _suite(function),
                "function_id": fid, "function_name": function, "maximization": False,
                "algorithm": {"name": algorithm, "info": alg_info},
                "attributes": ["evaluations", "raw_y"], "scenarios": []})
            meta["scenarios"].append({"dimension": dim, "path": rel, "runs": entries})
            continue
        infos.setdefault(folder / f"IOHprofiler_f{fid}_{name}.info", []).extend([
            f'suite = "{_suite(function)}", funcId = {fid}, funcName = "{function}", '
            f'DIM = {dim}, maximization = "F", algId = "{algorithm}", algInfo = "{alg_info}"',
            f"% swarmpath job {job_id}".rstrip(),
            ", ".join([rel, *(f"{e['instance']}:{e['evals']}|{_num(e['best']['y'])}"
                              for e in entries)]),
        ])
    for path, meta in metas.items():
        path.write_text(json.dumps(meta, indent=1) + "\n", encoding="ascii")
        out.files.append(path)
    for info, text in infos.items():
        info.write_text("\n".join(text) + "\n", encoding="ascii")
        out.files.append(info)
    return out


def _transform(spec: Mapping[str, Any]) -> str:
    """A cell's transform; specs written before transforms existed only say ``shifted``."""
    return str(spec.get("transform") or ("shift" if spec.get("shifted") else "none"))
