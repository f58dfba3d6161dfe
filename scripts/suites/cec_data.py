#!/usr/bin/env python3
"""Build (or check) the CEC 2017 / CEC 2022 package data from the organisers' ``input_data``.

The official codes read their shift vectors, rotation matrices and shuffles from text files in
an ``input_data`` directory (P. N. Suganthan's competition repositories; docs/functions.md names
them). This script parses those files the way the C code's ``fscanf("%lf")`` does (both round
the decimal text to the nearest double) and stores, per suite, one float64/int64 ``.npz``:

* ``O<f>``: every row of ``shift_data_<f>.txt`` (all 100 numbers of a row; the code reads the
  first D of row i for component i),
* ``M<f>_D<d>``: the first k (d, d) matrices of ``M_<f>_D<d>.txt``, k the components the
  function uses (1, or the composition's number of components),
* ``S<f>_D<d>``: ``shuffle_data_<f>_D<d>.txt`` as integers (1-based, as in the file),

plus ``manifest.json``: each source file's SHA-256 and which arrays came from it.

    scripts/suites/cec_data.py build cec2017 PATH/TO/input_data
    scripts/suites/cec_data.py check cec2017 PATH/TO/input_data   # every array == its text

``check`` re-reads every text file and compares it number for number (bit for bit) with the
shipped arrays; it exits 1 naming the first difference.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "services" / "swarmpath" / "functions" / "suites" / "data"

#: suite -> (dimensions, {function: matrices used}, functions with shuffles, components of them)
LAYOUT: dict[str, tuple[tuple[int, ...], dict[int, int], dict[int, int]]] = {
    "cec2017": (
        (10, 30, 50, 100),
        {**{f: 1 for f in range(1, 21)}, 21: 3, 22: 3, 23: 4, 24: 4, 25: 5, 26: 5, 27: 6, 28: 6,
         29: 3, 30: 3},
        {**{f: 1 for f in range(11, 21)}, 29: 10, 30: 10},
    ),
    "cec2022": (
        (10, 20),
        {**{f: 1 for f in range(1, 9)}, 9: 5, 10: 3, 11: 5, 12: 6},
        {6: 1, 7: 1, 8: 1},
    ),
}


def numbers(path: Path) -> list[str]:
    return path.read_text(encoding="ascii").split()


def parse(path: Path, kind: type = float) -> np.ndarray:
    words = numbers(path)
    if kind is int:
        return np.array([int(w) for w in words], dtype=np.int64)
    return np.array([float(w) for w in words], dtype=np.float64)


def arrays(suite: str, source: Path) -> tuple[dict[str, np.ndarray], dict[str, dict[str, str]]]:
    dims, matrices, shuffles = LAYOUT[suite]
    out: dict[str, np.ndarray] = {}
    files: dict[str, dict[str, str]] = {}

    def note(path: Path, key: str) -> None:
        entry = files.setdefault(path.name, {
            "sha256": hashlib.sha256(path.read_bytes()).hexdigest(), "arrays": ""})
        entry["arrays"] = " ".join(filter(None, [entry["arrays"], key]))

    for f, k in matrices.items():
        path = source / f"shift_data_{f}.txt"
        rows = [np.array([float(w) for w in line.split()]) for line in
                path.read_text(encoding="ascii").splitlines() if line.strip()]
        width = min(len(r) for r in rows)
        out[f"O{f}"] = np.stack([r[:width] for r in rows])
        note(path, f"O{f}")
        for d in dims:
            path = source / f"M_{f}_D{d}.txt"
            values = parse(path)
            out[f"M{f}_D{d}"] = values[: k * d * d].reshape(k, d, d)
            note(path, f"M{f}_D{d}")
            if f in shuffles:
                path = source / f"shuffle_data_{f}_D{d}.txt"
                out[f"S{f}_D{d}"] = parse(path, int)[: shuffles[f] * d].reshape(shuffles[f], d)
                note(path, f"S{f}_D{d}")
    return out, files


def build(suite: str, source: Path) -> None:
    out, files = arrays(suite, source)
    DATA.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(DATA / f"{suite}.npz", **out)
    manifest_path = DATA / "manifest.json"
    manifest = json.loads(manifest_path.read_text()) if manifest_path.exists() else {}
    manifest[suite] = {"files": files, "arrays": {
        key: hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()
        for key, a in sorted(out.items())}}
    manifest_path.write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    print(f"{suite}: {len(out)} arrays from {len(files)} files -> {DATA / (suite + '.npz')}")


def check(suite: str, source: Path) -> int:
    expected, _ = arrays(suite, source)
    with np.load(DATA / f"{suite}.npz") as shipped:
        if set(shipped.files) != set(expected):
            print(f"{suite}: arrays differ: {sorted(set(shipped.files) ^ set(expected))}")
            return 1
        for key, want in expected.items():
            got = shipped[key]
            if got.dtype != want.dtype or got.shape != want.shape or not np.array_equal(
                    got.view(np.uint8), want.view(np.uint8)):
                print(f"{suite}: {key} differs from its text file")
                return 1
    count = sum(a.size for a in expected.values())
    print(f"{suite}: {len(expected)} arrays, {count} numbers equal to the text files bit for bit")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("build", "check"))
    parser.add_argument("suite", choices=sorted(LAYOUT))
    parser.add_argument("input_data", type=Path, help="the organisers' input_data directory")
    args = parser.parse_args(argv)
    if args.action == "build":
        build(args.suite, args.input_data)
        return 0
    return check(args.suite, args.input_data)


if __name__ == "__main__":
    sys.exit(main())
