"""bbob against COCO's own cocoex, live: fresh points, dimensions and instances that the golden
values do not hold (coco-experiment is in the test extra, so CI runs this)."""

from __future__ import annotations

import numpy as np
import pytest

from swarmpath.functions import get_function
from swarmpath.functions.suites import golden

cocoex = pytest.importorskip("cocoex", reason="needs coco-experiment (pip install "
                             "'swarmpath[test]')")


@pytest.mark.parametrize("number", range(1, 25))
def test_bbob_equals_cocoex(number):
    rng = np.random.default_rng(number)
    base = get_function(f"bbob:f{number}")
    for dim, instance in ((4, 3), (7, 15), (13, 101), (40, 5), (2, 1000)):
        fn = base.with_instance(instance)
        problem = cocoex.BareProblem("bbob", number, dim, instance)
        X = rng.uniform(-5.0, 5.0, (60, dim))
        X = np.vstack([X, fn.x_opt(dim), np.clip(fn.x_opt(dim) + rng.normal(0, 1e-3, dim), -5, 5)])
        ref = np.array([problem(x) for x in X])
        ok = golden.agree(fn.value(X), ref, fn.f_opt(dim))
        assert ok.all(), (dim, instance, np.flatnonzero(~ok))
        assert golden.agree(np.array([fn.f_opt(dim)]), np.array([problem(fn.x_opt(dim))]),
                            fn.f_opt(dim)).all()
        assert np.allclose(np.asarray(problem.best_parameter()), fn.x_opt(dim), rtol=0,
                           atol=1e-12)
        assert golden.agree(np.array([fn.f_opt(dim)]), np.array([problem.best_value()]),
                            fn.f_opt(dim)).all()
