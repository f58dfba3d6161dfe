"""The registration path: register_function / register_suite / register, name expansion over
registered functions, origins and clashes, entry points, --plugin and SWARMPATH_PLUGINS."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from swarmpath.functions import (
    BenchmarkFunction,
    Suite,
    expand_function_names,
    get_function,
    get_suite,
    list_functions,
    list_suites,
    register_function,
    register_suite,
)
from swarmpath.functions.registry import REGISTRY as FUNCTIONS
from swarmpath.functions.registry import SUITES, unregister_suite
from swarmpath.optimizers import Optimizer, list_optimizers, minimize, register
from swarmpath.optimizers.gwo import GWO
from swarmpath.optimizers.registry import REGISTRY as OPTIMIZERS
from swarmpath.plugins import ExtensionClash


def _sphere_plus_one(x: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", x, x) + 1.0


def _numbered(prefix: str, numbers: list[int]) -> list[BenchmarkFunction]:
    return [BenchmarkFunction(f"{prefix}{i}", _sphere_plus_one, -5.0, 5.0, 0.0,
                              f_min_constant=1.0) for i in numbers]


@pytest.fixture
def scratch():
    """Names registered by a test are removed after it."""
    before = (set(FUNCTIONS.names()), set(SUITES.names()), set(OPTIMIZERS.names()))
    yield
    for name in set(SUITES.names()) - before[1]:
        unregister_suite(name)
    for registry, names in ((FUNCTIONS, before[0]), (OPTIMIZERS, before[2])):
        for name in set(registry.names()) - names:
            registry.unregister(name)


def test_builtins_are_builtin_and_listed_first():
    assert list_functions(builtin=True) == list_functions()[: len(list_functions(builtin=True))]
    assert FUNCTIONS.origin("F1").builtin and FUNCTIONS.origin("F1").describe() == "built-in"
    assert OPTIMIZERS.origin("GWO").digest == OPTIMIZERS.origin("GWO").digest
    assert len(OPTIMIZERS.origin("GWO").digest) == 64
    assert OPTIMIZERS.origin("GWO").digest != OPTIMIZERS.origin("PSO").digest
    assert list_suites(builtin=True) == ["bbob", "cec2017", "cec2022"]
    assert SUITES.origin("bbob").builtin


def test_registered_function_runs_and_ranges_cover_it(scratch):
    for fn in _numbered("F", [14, 15, 16]):
        register_function(fn)
    assert list_functions()[-3:] == ["F14", "F15", "F16"]
    assert not FUNCTIONS.origin("F14").builtin
    assert expand_function_names("F12-F16") == ["F12", "F13", "F14", "F15", "F16"]
    assert expand_function_names("F15-16") == ["F15", "F16"]
    with pytest.raises(KeyError, match="F17 is not registered"):
        expand_function_names("F1-F17")
    res = minimize("GWO", "F15", dim=3, agents=6, iterations=5, runs=2, seed=1)
    assert np.all(res.best_fitness >= 1.0)


def test_suite_expands_in_order_and_skips_left_out_members(scratch):
    fns = _numbered("toy:f", [1, 3, 4, 10])
    register_suite(Suite("toy", tuple(fns), ("toy:f1", "toy:f4", "toy:f10"), "a toy suite"))
    assert expand_function_names("toy") == ["toy:f1", "toy:f4", "toy:f10"]
    assert expand_function_names("TOY,F1") == ["toy:f1", "toy:f4", "toy:f10", "F1"]
    assert expand_function_names("toy:f3-f10") == ["toy:f4", "toy:f10"]
    assert expand_function_names("toy:f3") == ["toy:f3"]  # left out of the set, still named
    assert get_suite("toy").description == "a toy suite"
    assert not SUITES.origin("toy").builtin
    assert "test_plugins_registry.py" in SUITES.origin("toy").label
    with pytest.raises(KeyError, match="toyy"):
        expand_function_names("toyy")
    with pytest.raises(ValueError, match="named 'toy2:<name>'"):
        register_suite(Suite("toy2", tuple(_numbered("toy:g", [1]))))


def test_suite_name_must_not_be_a_function_name(scratch):
    with pytest.raises(ExtensionClash, match="has the name of the function"):
        register_suite(Suite("F1", tuple(_numbered("F1:x", [1]))))


def test_clash_names_both_origins(scratch):
    other = BenchmarkFunction("F1", _sphere_plus_one, -1.0, 1.0, 0.0)
    with pytest.raises(ExtensionClash) as err:
        register_function(other)
    message = str(err.value)
    assert "function 'F1' from file" in message and "test_plugins_registry.py" in message
    assert "from built-in" in message
    assert get_function("F1").lower == -100.0  # the built-in stays


def test_register_checks_what_it_is_given(scratch):
    with pytest.raises(TypeError, match="Optimizer subclass"):
        register(object)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="BenchmarkFunction"):
        register_function("F1")  # type: ignore[arg-type]

    class Bad(Optimizer):
        name = "a,b"

        def _initialize(self): ...

        def _iterate(self): ...

    with pytest.raises(ValueError, match="comma"):
        register(Bad)


def test_registering_the_same_code_again_replaces(scratch):
    @register
    class Mine(GWO):
        name = "MineGWO"

    @register
    class Mine2(GWO):  # same file: a reload of the same code, not a clash
        name = "MineGWO"

    assert OPTIMIZERS.get("MineGWO") is Mine2
    assert list_optimizers().count("MineGWO") == 1
    assert "MineGWO" in list_optimizers(builtin=False)
    assert "MineGWO" not in list_optimizers(builtin=True)


def test_per_coordinate_box_and_fixed_dimension(scratch):
    fn = BenchmarkFunction("box3", _sphere_plus_one, (0.0, -1.0, 2.0), (1.0, 1.0, 3.0),
                           (0.0, 0.0, 2.0), f_min_constant=5.0)
    assert fn.dimensions == (3,)
    with pytest.raises(ValueError, match="defined for dim in 3"):
        fn.check_dim(4)
    register_function(fn)
    res = minimize("PSO", "box3", dim=3, agents=8, iterations=10, runs=2, seed=2)
    lower, upper = fn.bounds(3)
    assert np.all(res.best_position >= lower) and np.all(res.best_position <= upper)
    from swarmpath.optimizers import ParameterError

    with pytest.raises(ParameterError, match="defined for dim in 3"):
        minimize("PSO", "box3", dim=4, agents=8, iterations=2, runs=1)


def test_unknown_minimiser_refuses_transforms(scratch):
    register_function(BenchmarkFunction("nomin", _sphere_plus_one, -1.0, 1.0, None))
    from swarmpath.optimizers import ParameterError

    with pytest.raises(ParameterError, match="no known minimiser"):
        minimize("GWO", "nomin", dim=2, agents=5, iterations=2, runs=1, transform="shift")
    assert minimize("GWO", "nomin", dim=2, agents=5, iterations=2, runs=1).best_fitness.size == 1


# ------------------------------------------------------------------- processes and entry points
PLUGIN = textwrap.dedent('''
    import numpy as np
    from swarmpath.functions import BenchmarkFunction, register_function
    from swarmpath.optimizers import register
    from swarmpath.optimizers.gwo import GWO


    @register
    class FileGWO(GWO):
        name = "FileGWO"


    def _shifted_sphere(x):
        return np.einsum("...i,...i->...", x - 1.0, x - 1.0)


    register_function(BenchmarkFunction("F14", _shifted_sphere, -10.0, 10.0, 1.0))
''')


def _run(args: list[str], env: dict[str, str] | None = None):
    full = {k: v for k, v in os.environ.items() if k != "SWARMPATH_PLUGINS"}
    full.update(env or {})
    return subprocess.run([sys.executable, "-m", "swarmpath.cli", *args], capture_output=True,
                          text=True, env=full, timeout=300)


def test_plugin_file_runs_in_bench_and_in_j2_children(tmp_path):
    plugin = tmp_path / "my_plugin.py"
    plugin.write_text(PLUGIN)
    common = ["bench", "-a", "FileGWO,GWO", "-f", "F1,F14", "-d", "3", "--runs", "3",
              "--agents", "6", "--iterations", "8", "--json"]
    one = _run([*common, "--plugin", str(plugin)])
    assert one.returncode == 0, one.stderr
    two = _run([*common, "-j", "2", "--plugin", str(plugin)])
    assert two.returncode == 0, two.stderr
    env = _run(common, env={"SWARMPATH_PLUGINS": str(plugin)})
    assert env.returncode == 0, env.stderr
    runs = [{(c["algorithm"], c["function"]): c["best_fitness"]
             for c in json.loads(p.stdout)["cells"]} for p in (one, two, env)]
    assert runs[0] == runs[1] == runs[2]
    for function in ("F1", "F14"):  # FileGWO is GWO under another name: the same runs
        assert runs[0][("FileGWO", function)] == runs[0][("GWO", function)]


def test_plugin_errors_exit_2_naming_the_source(tmp_path):
    missing = _run(["bench", "-a", "GWO", "-f", "F1", "--plugin", str(tmp_path / "no.py")])
    assert missing.returncode == 2 and "--plugin:" in missing.stderr
    assert "is not a file" in missing.stderr and "Traceback" not in missing.stderr
    env = _run(["bench", "-a", "GWO", "-f", "F1"], env={"SWARMPATH_PLUGINS": "no_such_mod_x"})
    assert env.returncode == 2
    assert "SWARMPATH_PLUGINS: no module named 'no_such_mod_x'" in env.stderr
    broken = tmp_path / "broken.py"
    broken.write_text("raise RuntimeError('half written')\n")
    out = _run(["plan", "--list-maps", "--plugin", str(broken)])
    assert out.returncode == 2 and "RuntimeError: half written" in out.stderr
    clash = tmp_path / "clash.py"
    clash.write_text("from swarmpath.optimizers import register\n"
                     "from swarmpath.optimizers.pso import PSO\n"
                     "@register\nclass P(PSO):\n    name = 'GWO'\n")
    out = _run(["bench", "-a", "GWO", "-f", "F1", "--plugin", str(clash)])
    assert out.returncode == 2
    assert f"optimizer 'GWO' from file {clash}" in out.stderr and "from built-in" in out.stderr


def _distribution(root: Path, name: str, entry_points: str, code: str) -> None:
    """An installed distribution as importlib.metadata finds it: a package and its dist-info."""
    package = root / name
    package.mkdir(parents=True)
    (package / "__init__.py").write_text(code)
    info = root / f"{name}-1.2.3.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 1.2.3\n")
    (info / "entry_points.txt").write_text(entry_points)
    (info / "top_level.txt").write_text(name + "\n")


def test_entry_points_load_with_their_distribution(tmp_path):
    code = PLUGIN.replace("@register\n", "") + textwrap.dedent('''
        from swarmpath.functions import Suite
        TWO = Suite("pair", (BenchmarkFunction("pair:f1", _shifted_sphere, -3.0, 3.0, 1.0),
                             BenchmarkFunction("pair:f2", _shifted_sphere, -4.0, 4.0, 1.0)))
    ''').replace('register_function(BenchmarkFunction("F14"', 'F14 = (BenchmarkFunction("F14"')
    _distribution(tmp_path, "epplug", textwrap.dedent('''
        [swarmpath.optimizers]
        FileGWO = epplug:FileGWO
        [swarmpath.functions]
        F14 = epplug:F14
        pair = epplug:TWO
    '''), code)
    env = {"PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    script = textwrap.dedent('''
        from swarmpath.functions import expand_function_names, list_functions
        from swarmpath.functions.registry import function_origin
        from swarmpath.optimizers import list_optimizers
        from swarmpath.optimizers.registry import REGISTRY as O
        o = O.origin("FileGWO")
        print(list_optimizers()[-1], o.describe(), len(o.digest))
        print(expand_function_names("pair,F13-F14"))
        print(function_origin("pair:f2").describe())
    ''')
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         env={**os.environ, **env}, timeout=120)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "FileGWO distribution epplug 1.2.3 64"
    assert lines[1] == "['pair:f1', 'pair:f2', 'F13', 'F14']"
    assert lines[2] == "distribution epplug 1.2.3"


def test_broken_entry_point_is_left_out_and_reported(tmp_path):
    _distribution(tmp_path, "badplug", "[swarmpath.optimizers]\nBad = badplug:Nothing\n",
                  "x = 1\n")
    env = {"PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    script = ("from swarmpath.optimizers import list_optimizers; "
              "from swarmpath.plugins import problems; "
              "print(len(list_optimizers())); print(problems()[0].message)")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         env={**os.environ, **env}, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.splitlines()[0] == str(len(list_optimizers(builtin=True)))  # no "Bad"
    assert "AttributeError" in out.stdout and "left out" in out.stderr


def _file_digest(path: Path) -> str:
    """The documented digest of a one-file plugin, computed here from the definition."""
    import hashlib

    data = path.read_bytes()
    return hashlib.sha256(path.name.encode() + b"\0" + str(len(data)).encode() + b"\0"
                          + data).hexdigest()


def test_plugins_lists_every_extension_with_origin_and_digest(tmp_path):
    plugin = tmp_path / "my_plugin.py"
    plugin.write_text(PLUGIN)
    out = _run(["plugins", "--json", "--plugin", str(plugin)])
    assert out.returncode == 0, out.stderr
    rows = {(r["kind"], r["name"]): r for r in json.loads(out.stdout)["extensions"]}
    mine = rows[("optimizer", "FileGWO")]
    assert mine["source"] == "file" and mine["label"] == str(plugin)
    assert mine["digest"] == _file_digest(plugin)
    assert mine["defaults"] == rows[("optimizer", "GWO")]["defaults"]
    assert mine["choices"]["leaders"] == ["authors", "elitist"]
    assert rows[("function", "F14")]["digest"] == _file_digest(plugin)
    assert rows[("optimizer", "GWO")]["origin"] == "built-in"
    assert {("suite", "bbob"), ("planner", "ICOOT"), ("function", "F1")} <= set(rows)
    text = _run(["plugins", "--only-plugins", "--plugin", str(plugin)])
    lines = text.stdout.splitlines()
    assert lines[0].split()[:4] == ["kind", "name", "source", "digest"]
    assert [ln.split()[1] for ln in lines[1:]] == ["FileGWO", "F14"]
    assert _file_digest(plugin)[:12] in lines[1]
    plugin.write_text(PLUGIN + "\n# edited\n")  # another version of the code: another digest
    again = json.loads(_run(["plugins", "--json", "--plugin", str(plugin)]).stdout)
    edited = next(r for r in again["extensions"] if r["name"] == "FileGWO")
    assert edited["digest"] == _file_digest(plugin) != mine["digest"]


def test_catalog_carries_origins_and_digests():
    from swarmpath.service.catalog import build_catalog

    cat = build_catalog()
    gwo = next(o for o in cat["optimizers"] if o["name"] == "GWO")
    assert gwo["source"] == "built-in" and len(gwo["digest"]) == 64
    assert gwo["digest"] == OPTIMIZERS.origin("GWO").digest
    assert all(len(f["digest"]) == 64 for f in cat["functions"])
    assert {s["origin"] for s in cat["suites"]} == {"built-in"}
    assert all(p["source"] == "built-in" for p in cat["planners"])
    assert cat["plugin_problems"] == []
