"""``swarmpath warmup`` and ``compiled.warm``: the kernels a study needs, made ready before it."""

import json

import numpy as np
from typer.testing import CliRunner

from swarmpath.cli import app
from swarmpath.optimizers import minimize
from swarmpath.optimizers.compiled import kernel_names
from swarmpath.optimizers.compiled.objectives import compiled_names
from swarmpath.optimizers.compiled.warm import warm

runner = CliRunner()


def test_warm_makes_the_named_pieces_ready_and_times_each():
    done = warm(["PSO"], ["F9", "F1"])
    assert [(w.kind, w.name) for w in done] == [
        ("function", "F9"), ("function", "F1"), ("algorithm", "PSO")]
    ref = minimize("PSO", "F9", dim=3, agents=6, iterations=4, runs=2, backend="numpy")
    fast = minimize("PSO", "F9", dim=3, agents=6, iterations=4, runs=2)
    assert fast.backend == "numba" and np.array_equal(ref.curve, fast.curve)


def test_warmup_command_lists_what_it_compiled():
    out = runner.invoke(app, ["warmup", "-a", "PSO,GWO", "-f", "F1-F2", "--json"])
    assert out.exit_code == 0, out.output
    names = [(w["kind"], w["name"]) for w in json.loads(out.stdout)]
    assert names == [("function", "F1"), ("function", "F2"), ("algorithm", "PSO"),
                     ("algorithm", "GWO")]
    assert set(kernel_names()) >= {"PSO", "GWO"} and "F1" in compiled_names()


def test_warmup_names_the_option_of_what_has_no_kernel():
    for args, field in ((["-a", "NOPE"], "--algorithms"), (["-a", "RS"], "--algorithms"),
                        (["-f", "cec2022:F1"], "--functions"), (["-f", "F99"], "--functions")):
        out = runner.invoke(app, ["warmup", *args])
        assert out.exit_code == 2, (args, out.output)
        assert f"error: {field}:" in out.output, (args, out.output)
