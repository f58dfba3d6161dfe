"""Per-run exports of a job: one row per run with its identity and metrics, as CSV, JSON or
Parquet, and :func:`load_results` into a pandas DataFrame.

A row is built from a run item of the coordinator (``GET /jobs/{id}/runs?format=jsonl``, which
carries the cell ``spec`` and the series). Columns come from one place per kind:
:data:`BENCHMARK_COLUMNS` and, for map jobs, the identity columns plus the fields of
:class:`swarmpath.planners.episode.RunOutcome` (so a metric added there is exported too).
List columns (``curve``, ``best_position``, ``path``) are lists in JSON and Parquet (Parquet
``list<double>`` and ``list<list<double>>``) and JSON text in CSV.

pandas and pyarrow are the optional extra ``data`` (``pip install swarmpath[data]``).
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import math
import typing
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import pydantic_core

#: (name, type) of a benchmark run's row; type is one of int, float, bool, str, "list",
#: "list2" (a list of rows).
BENCHMARK_COLUMNS: tuple[tuple[str, Any], ...] = (
    ("job_id", str), ("run_id", int), ("run", int), ("cell", str), ("algorithm", str),
    ("function", str), ("dim", int), ("agents", int), ("iterations", int), ("shifted", bool),
    ("transform", str), ("seed", int), ("state", str), ("worker", str), ("best_fitness", float),
    ("evaluations", int), ("seconds", float), ("cpu_seconds", float), ("failure", str),
    ("completed", float),
    ("curve_stride", int), ("curve", "list"), ("best_position", "list"),
)
MAP_IDENTITY: tuple[tuple[str, Any], ...] = (
    ("job_id", str), ("run_id", int), ("run", int), ("cell", str), ("planner", str),
    ("map", str), ("bucket", int), ("seed", int), ("state", str), ("worker", str),
)
MAP_TAIL: tuple[tuple[str, Any], ...] = (
    ("failure", str), ("completed", float), ("curve_stride", int), ("path", "list2"),
)
FORMATS = ("csv", "json", "parquet")
NEEDS_DATA_EXTRA = "needs pandas and pyarrow: pip install 'swarmpath[data]'"


def map_columns() -> tuple[tuple[str, Any], ...]:
    """Identity, then every RunOutcome field (the metrics of ``swarmpath plan --json``)."""
    from swarmpath.planners.episode import RunOutcome

    hints = typing.get_type_hints(RunOutcome)
    seen = {n for n, _ in MAP_IDENTITY} | {n for n, _ in MAP_TAIL}
    middle = []
    for name, hint in hints.items():
        if name in seen:
            continue
        args = [a for a in typing.get_args(hint) if a is not type(None)] or [hint]
        base = args[0] if args[0] in (int, float, bool, str) else str
        middle.append((name, base))
    return (*MAP_IDENTITY, *middle, *MAP_TAIL)


def columns(kind: str) -> tuple[tuple[str, Any], ...]:
    if kind == "benchmark":
        return BENCHMARK_COLUMNS
    if kind == "map":
        return map_columns()
    raise ValueError(f"unknown job kind {kind!r}")


def kind_of(item: Mapping[str, Any]) -> str:
    return "benchmark" if "algorithm" in item else "map"


def _number(v: Any, kind: Any) -> Any:
    """JSON's "inf"/"nan" strings back to floats; None stays None."""
    if v is None:
        return None
    if kind is float:
        return float(v)
    if kind is int:
        return int(v)
    if kind is bool:
        return bool(v)
    return v


def run_row(item: Mapping[str, Any], job_id: str | None = None) -> dict[str, Any]:
    """One run item (with ``spec`` and series) as a row of :func:`columns` of its kind."""
    kind = kind_of(item)
    spec = item.get("spec") or {}
    out: dict[str, Any] = {}
    for name, typ in columns(kind):
        if name == "job_id":
            v = job_id if job_id is not None else item.get("job_id")
        elif name in ("agents", "iterations", "shifted") and kind == "benchmark":
            v = item.get(name, spec.get(name))
        elif name == "transform" and kind == "benchmark":
            v = item.get(name, spec.get(name, "shift" if spec.get("shifted") else "none"))
        else:
            v = item.get(name)
        if typ == "list":
            v = None if v is None else [_number(x, float) for x in v]
        elif typ == "list2":
            v = None if v is None else [[_number(x, float) for x in row] for row in v]
        elif typ in (int, float, bool):
            v = _number(v, typ)
        elif v is not None and not isinstance(v, str):
            v = json.dumps(v)
        out[name] = v
    return out


def rows(items: Iterable[Mapping[str, Any]], job_id: str | None = None) -> Iterator[dict]:
    for item in items:
        yield run_row(item, job_id)


# ------------------------------------------------------------------------------------ writers
def _csv_value(v: Any) -> Any:
    if v is None:
        return ""
    if isinstance(v, list):  # JSON text (Infinity/NaN as json.loads reads them); the Rust
        # serializer: json.dumps spent 1 ms per 500-value curve on float formatting
        return pydantic_core.to_json(v, inf_nan_mode="constants").decode()
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    return v


def csv_chunks(kind: str, row_iter: Iterable[Mapping[str, Any]], batch: int = 500
               ) -> Iterator[str]:
    """CSV text in chunks: the header, then ``batch`` rows per chunk (list columns as JSON)."""
    names = [n for n, _ in columns(kind)]
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(names)
    n = 0
    for row in row_iter:
        writer.writerow([_csv_value(row.get(c)) for c in names])
        n += 1
        if n % batch == 0:
            yield buf.getvalue()
            buf.seek(0)
            buf.truncate()
    yield buf.getvalue()


def _json_value(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, list):
        return [_json_value(x) for x in v]
    return v


def json_row(row: Mapping[str, Any]) -> dict[str, Any]:
    """A row for strict JSON (non-finite floats as the strings "inf", "-inf", "nan")."""
    return {k: _json_value(v) for k, v in row.items()}


def arrow_schema(kind: str) -> Any:
    import pyarrow as pa

    types = {int: pa.int64(), float: pa.float64(), bool: pa.bool_(), str: pa.string(),
             "list": pa.list_(pa.float64()), "list2": pa.list_(pa.list_(pa.float64()))}
    return pa.schema([(n, types[t]) for n, t in columns(kind)])


def parquet_chunks(kind: str, row_iter: Iterable[Mapping[str, Any]], batch: int = 500
                   ) -> Iterator[bytes]:
    """A Parquet file in chunks (one row group per ``batch`` rows), written as it is read."""
    import pyarrow.parquet as pq

    schema = arrow_schema(kind)
    sink = io.BytesIO()
    writer = pq.ParquetWriter(sink, schema, compression="zstd")
    pending: list[Mapping[str, Any]] = []

    def drain() -> bytes:
        data = sink.getvalue()
        sink.seek(0)
        sink.truncate()
        return data

    for row in row_iter:
        pending.append(row)
        if len(pending) >= batch:
            writer.write_table(arrow_table(kind, pending, schema))
            pending = []
            yield drain()
    if pending:
        writer.write_table(arrow_table(kind, pending, schema))
    writer.close()
    yield drain()


def arrow_table(kind: str, batch: list[Mapping[str, Any]], schema: Any) -> Any:
    """Rows as a pyarrow Table; ``list<double>`` columns built from one flat numpy array
    (pyarrow's per-value conversion of Python lists was most of an export's time)."""
    import numpy as np
    import pyarrow as pa

    arrays = []
    for (name, typ), field in zip(columns(kind), schema, strict=True):
        values = [row.get(name) for row in batch]
        if typ == "list":
            lengths = np.fromiter((0 if v is None else len(v) for v in values), np.int32,
                                  count=len(values))
            offsets = np.concatenate([[0], np.cumsum(lengths, dtype=np.int32)])
            flat = np.fromiter(itertools.chain.from_iterable(v for v in values if v), float,
                               count=int(offsets[-1]))
            missing = pa.array([v is None for v in values])
            arrays.append(pa.ListArray.from_arrays(pa.array(offsets), pa.array(flat),
                                                   mask=missing))
        else:
            arrays.append(pa.array(values, type=field.type))
    return pa.Table.from_arrays(arrays, schema=schema)


def write(kind: str, row_iter: Iterable[Mapping[str, Any]], fmt: str, path: Path) -> int:
    """Write rows to ``path`` (csv, json or parquet) through ``path.part``; returns the count."""
    if fmt not in FORMATS:
        raise ValueError(f"format {fmt!r} is not one of {', '.join(FORMATS)}")
    counted = _Counter(row_iter)
    tmp = path.with_name(path.name + ".part")
    if fmt == "csv":
        with open(tmp, "w", encoding="utf-8", newline="") as f:
            for text in csv_chunks(kind, counted):
                f.write(text)
    elif fmt == "parquet":
        with open(tmp, "wb") as f:
            for data in parquet_chunks(kind, counted):
                f.write(data)
    else:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write("[")
            for i, row in enumerate(counted):
                f.write(("," if i else "") + "\n" + pydantic_core.to_json(json_row(row)).decode())
            f.write("\n]\n")
    tmp.replace(path)
    return counted.n


class _Counter:
    def __init__(self, it: Iterable[Mapping[str, Any]]):
        self.it, self.n = it, 0

    def __iter__(self) -> Iterator[Mapping[str, Any]]:
        for row in self.it:
            self.n += 1
            yield row


# ---------------------------------------------------------------------------------- loading
def _pandas() -> Any:
    try:
        import pandas as pd
    except ImportError:
        raise ImportError(f"load_results {NEEDS_DATA_EXTRA}") from None
    return pd


def frame(row_list: list[Mapping[str, Any]], kind: str) -> Any:
    """Rows as a DataFrame with the export's columns (in order, even when there is no row)."""
    pd = _pandas()
    names = [n for n, _ in columns(kind)]
    return pd.DataFrame(list(row_list), columns=names)


def _parse_list(v: Any) -> Any:
    if isinstance(v, str) and v.startswith("["):
        return json.loads(v)
    return None if isinstance(v, float) and math.isnan(v) else v


def read_file(path: Path) -> Any:
    """A file written by :func:`write` (by its suffix) as a DataFrame; list columns as lists."""
    pd = _pandas()
    suffix = path.suffix.lower()
    if suffix == ".parquet":
        return pd.read_parquet(path)
    if suffix == ".csv":
        df = pd.read_csv(path, keep_default_na=True)
        kind = "benchmark" if "algorithm" in df.columns else "map"
        for name, typ in columns(kind):
            if typ in ("list", "list2") and name in df.columns:
                df[name] = df[name].map(_parse_list)
        return df
    if suffix in (".json", ".jsonl"):
        text = path.read_text(encoding="utf-8")
        data = ([json.loads(line) for line in text.splitlines() if line.strip()]
                if suffix == ".jsonl" else json.loads(text))
        if not data:
            return pd.DataFrame()
        kind = kind_of(data[0])
        return frame([run_row(d) if "spec" in d else d for d in data], kind)
    raise ValueError(f"{path}: not a .csv, .json, .jsonl or .parquet export")


def load_results(source: str | Path, url: str | None = None) -> Any:
    """A job's runs as a pandas DataFrame, one row per run (see the module doc for columns).

    ``source``: an export file (``.csv``, ``.json``, ``.jsonl``, ``.parquet``) or a job id
    fetched from the coordinator at ``url`` (default ``$SWARMPATH_URL`` or
    http://127.0.0.1:8000; token from ``$SWARMPATH_TOKEN``)."""
    path = Path(source)
    if path.suffix.lower() in (".csv", ".json", ".jsonl", ".parquet") or path.is_file():
        return read_file(path)
    from swarmpath.service.client import ServiceClient

    with ServiceClient(url) as client:
        job = str(source)
        kind = client.job(job)["kind"]
        return frame(list(rows(client.iter_runs(job), job)), kind)
