"""The suites against their references' golden values (tests/data/golden, made by
scripts/suites/golden.py from cocoex and the organisers' CEC codes): every function, every
dimension, three instances (CEC: the official one), 1,000 box points, the optimum and 23 points
around it, within golden.RTOL of max(|f|, |f - f_opt|)."""

from __future__ import annotations

import hashlib
import json
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from swarmpath.functions import get_function, list_functions, list_suites
from swarmpath.functions.suites import cec, golden

GOLDEN = Path(__file__).parent / "data" / "golden"
DATA = Path(cec.__file__).parent / "data"


@cache
def reference(suite: str) -> dict[str, np.ndarray]:
    with np.load(GOLDEN / f"{suite}.npz") as npz:
        return {k: npz[k] for k in npz.files}


def test_every_function_dimension_and_instance_has_golden_values():
    for suite in ("bbob", "cec2017", "cec2022"):
        assert suite in list_suites()
        keys = {golden.key(*case) for case in golden.cases(suite)}
        assert set(reference(suite)) == keys, suite
    assert len(golden.cases("bbob")) == 24 * 6 * 3
    assert len(golden.cases("cec2017")) == 30 * 4 and len(golden.cases("cec2022")) == 12 * 2


@pytest.mark.parametrize("name", [n for s in ("bbob", "cec2017", "cec2022")
                                  for n in list_functions(s)])
def test_values_equal_the_reference(name):
    suite = name.split(":")[0]
    table = reference(suite)
    base = get_function(name)
    for _, dim, instance in [c for c in golden.cases(suite) if c[0] == name]:
        fn = base.with_instance(instance)
        stored = table[golden.key(name, dim, instance)]
        ref, f_opt = stored[:-1], float(stored[-1])
        assert f_opt == fn.f_opt(dim)
        x_opt = fn.x_opt(dim)
        X = golden.points(dim, fn.lower, fn.upper, x_opt, golden.salt(fn.number, dim, instance))
        assert len(X) >= 1001 and np.array_equal(X[golden.BOX_POINTS], x_opt)
        ours = fn.value(X)
        ok = golden.agree(ours, ref, f_opt)
        bad = np.flatnonzero(~ok)
        assert bad.size == 0, (f"{name} d={dim} i={instance}: {bad.size} points differ, first "
                               f"{X[bad[0]]}: {ours[bad[0]]!r} vs {ref[bad[0]]!r}")
        # the optimum: the reference's value there is f_opt (within the agreement rule), and
        # the error the kernel reports is 0 there
        assert golden.agree(ref[golden.BOX_POINTS], f_opt, f_opt)
        assert abs(fn.kernel(x_opt[None])[0]) <= golden.RTOL * max(1.0, abs(f_opt))


def test_agreement_rule_can_fail():
    assert not golden.agree(np.array([100.0 + 1e-6]), np.array([100.0]), 0.0).any()
    assert golden.agree(np.array([np.inf]), np.array([np.inf]), 0.0).all()
    assert not golden.agree(np.array([1e300]), np.array([np.inf]), 0.0).any()


@pytest.mark.parametrize("suite", ["cec2017", "cec2022"])
def test_cec_data_is_what_the_manifest_names(suite):
    """Each shipped array hashes to the SHA-256 recorded when it was read from the organisers'
    text files (scripts/suites/cec_data.py check compares them with the text itself)."""
    manifest = json.loads((DATA / "manifest.json").read_text())[suite]
    arrays = cec.data(suite)
    assert set(arrays) == set(manifest["arrays"])
    for key, digest in manifest["arrays"].items():
        assert hashlib.sha256(np.ascontiguousarray(arrays[key]).tobytes()).hexdigest() == digest
    sources = {name for entry in manifest["files"].values() for name in entry["arrays"].split()}
    assert sources == set(arrays)
