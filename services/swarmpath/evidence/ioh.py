"""Convergence curves in the IOHprofiler format, which IOHanalyzer loads (``swarmpath results JOB
--format ioh -o DIR``).

The format (IOHanalyzer's "Supported Data Format" page, inst/shiny-server/markdown/dataformat.md
in github.com/IOHprofiler/IOHanalyzer, and the files IOHexperimenter writes): per algorithm a
folder holding, per function, a meta-data file ``IOHprofiler_f<id>_<name>.info`` with three lines
per dimension

* ``suite = "swarmpath", funcId = <id>, funcName = "<name>", DIM = <d>, maximization = "F",
  algId = "<algorithm>", algInfo = "..."`` (``funcId``, ``DIM`` and ``algId`` are mandatory),
* a line starting with ``%`` (a comment),
* the raw-data file's relative path, then ``<instance>:<evaluations>|<best-so-far f(x)>`` per run;

and the raw data ``data_f<id>_<name>/IOHprofiler_f<id>_DIM<d>.dat`` in the two-column format: per
run a separation line ``"function evaluation" "best-so-far f(x)"``, then one line per improvement
``<evaluations> <best-so-far>``, single-space separated, each block ending with the run's last
evaluation.

swarmpath records the best-so-far after each iteration. The evaluations after iteration k are
taken as ``round(N + k * (E - N) / T)`` (N: the agents, evaluated once before the first
iteration; E: the run's evaluations; T: the iterations), exact for the algorithms that evaluate
the initial population and then the same number of agents each iteration. A curve the service
thinned (``curve_stride`` s) has iterations 1, 1 + s, 1 + 2s, ... and the last one. Function ids
are the positions in the function registry (F1 = 1, ...). A suite function is written as its
suite has it (``suite = "bbob"``, ``funcId`` its number, ``funcName`` without the instance) and
the runs of all its instances go to one file, each with its instance id. Runs of a transformed
job (shift, rotate) are instances 1 + run (each run moves or turns the function); otherwise
every run is instance 1. Non-finite values (an infeasible start) are left out; a run without a
finite value is left out and counted.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

SEPARATOR = '"function evaluation" "best-so-far f(x)"'


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("_") or "x"


def function_id(name: str) -> int:
    """F1..F13's position in the registry; a suite function's number in its suite (bbob:f3 ->
    3, as COCO and IOHprofiler number them)."""
    from swarmpath.functions import get_function, list_functions

    if name in list_functions():
        return list_functions().index(name) + 1
    return int(getattr(get_function(name), "number", 0))


def _suite_of(name: str) -> tuple[str, str, int | None]:
    """(suite label, function name without its instance, instance) of a function name."""
    from swarmpath.functions.suites.base import split_instance

    base, instance = split_instance(name)
    suite, colon, _ = base.partition(":")
    if not colon:
        return "swarmpath", name, None
    return suite, base, 1 if instance is None else instance


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


def write_ioh(items: Iterable[Mapping[str, Any]], directory: Path, job_id: str = "") -> Written:
    """Write every finished benchmark run's curve under ``directory`` (see the module doc)."""
    groups: dict[tuple[str, str, int], list[Mapping[str, Any]]] = {}
    out = Written()
    for item in items:
        if item.get("state") != "done" or "algorithm" not in item:
            continue
        if not item.get("curve"):
            out.skipped += 1
            continue
        # a suite function's instances are runs of one function (instance ids in the .info)
        groups.setdefault((str(item["algorithm"]), _suite_of(str(item["function"]))[1],
                           int(item["dim"])), []).append(item)
    infos: dict[Path, list[str]] = {}
    for (algorithm, function, dim), runs in sorted(groups.items(),
                                                   key=lambda kv: (kv[0][0], function_id(kv[0][1]),
                                                                   kv[0][2])):
        fid = function_id(function)
        name = _slug(function)
        folder = directory / _slug(algorithm)
        rel = f"data_f{fid}_{name}/IOHprofiler_f{fid}_DIM{dim}.dat"
        dat_path = folder / rel
        dat_path.parent.mkdir(parents=True, exist_ok=True)
        entries: list[str] = []
        lines: list[str] = []
        spec: Mapping[str, Any] = {}
        suite = _suite_of(function)[0]
        for item in sorted(runs, key=lambda r: (_suite_of(str(r["function"]))[2] or 0,
                                                int(r["run"]))):
            spec = item.get("spec") or {}
            curve = list(item["curve"])
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
            lines.append(SEPARATOR)
            lines += [f"{e} {_num(v)}" for e, v in block]
            entries.append(f"{instance}:{block[-1][0]}|{_num(block[-1][1])}")
            out.runs += 1
        if not entries:
            continue
        dat_path.write_text("\n".join(lines) + "\n", encoding="ascii")
        out.files.append(dat_path)
        info = folder / f"IOHprofiler_f{fid}_{name}.info"
        # no commas inside values: the first line is split at commas into name = value pairs
        alg_info = (f"{spec.get('agents', '?')} agents; {spec.get('iterations', '?')} "
                    f"iterations; seed {runs[0].get('seed', '?')}"
                    + (f"; transform {_transform(spec)}" if _transform(spec) != "none" else ""))
        infos.setdefault(info, []).extend([
            f'suite = "{suite}", funcId = {fid}, funcName = "{function}", DIM = {dim}, '
            f'maximization = "F", algId = "{algorithm}", algInfo = "{alg_info}"',
            f"% swarmpath job {job_id}".rstrip(),
            ", ".join([rel, *entries]),
        ])
    for info, text in infos.items():
        info.write_text("\n".join(text) + "\n", encoding="ascii")
        out.files.append(info)
    return out


def _transform(spec: Mapping[str, Any]) -> str:
    """A cell's transform; specs written before transforms existed only say ``shifted``."""
    return str(spec.get("transform") or ("shift" if spec.get("shifted") else "none"))
