"""CEC 2017 (F1-F30) and CEC 2022 (F1-F12) bound-constrained functions with the official data.

Definitions: Awad, Ali, Liang, Qu, Suganthan, "Problem definitions and evaluation criteria for
the CEC 2017 special session and competition on single objective real-parameter numerical
optimization", Tech. Rep., NTU Singapore, 2016; Kumar, Price, Mohamed, Hadi, Suganthan,
"Problem definitions and evaluation criteria for the CEC 2022 special session and competition on
single objective bound constrained numerical optimization", Tech. Rep., NTU Singapore, 2021.
Values as the organisers' C codes compute them (``cec17_test_func``, ``cec22_test_func``), with
their shift vectors, rotation matrices and shuffles (package data ``data/cec2017.npz``,
``data/cec2022.npz``, built by ``scripts/suites/cec_data.py``). The box is [-100, 100]^D;
f_opt of F<k> is the bias the code adds (100 k for CEC 2017; 300, 400, 600, 800, 900, 1800,
2000, 2200, 2300, 2400, 2600, 2700 for CEC 2022).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmpath.functions.suites import cec_basic as b

Array = NDArray[np.float64]

BOUND = 100.0


@cache
def data(suite: str) -> dict[str, Array]:
    """The suite's arrays (read once per process from the package data)."""
    with resources.files("swarmpath.functions.suites").joinpath(
            f"data/{suite}.npz").open("rb") as handle, np.load(handle) as npz:
        out = {key: npz[key] for key in npz.files}
    for a in out.values():
        a.setflags(write=False)
    return out


def _o(suite: str, f: int) -> Array:
    return data(suite)[f"O{f}"]


def _m(suite: str, f: int, n: int) -> Array:
    return data(suite)[f"M{f}_D{n}"]


def _s(suite: str, f: int, n: int) -> Array:
    return data(suite)[f"S{f}_D{n}"]


# ------------------------------------------------------------------- basic and hybrid parts
def simple(name: str, x: Array, o: Array | None, m: Array | None, levy_shift: float) -> Array:
    """Basic function ``name`` at x, shifted by o and rotated by m as ``sr`` does (None: not)."""
    if name == "bi_rastrigin":
        assert o is not None
        return b.bi_rastrigin(x, o, m, shifted=True)
    z, y = b.sr(x, o, m, b.RATE.get(name, 1.0))
    if name == "schaffer_f7":
        return b.schaffer_f7(y)
    if name == "levy":
        return b.levy(z, levy_shift)
    fn: Callable[[Array], Array] = getattr(b, "rastrigin" if name == "step_rastrigin" else name)
    return fn(z)


def hybrid(parts: tuple[str, ...], shares: tuple[float, ...], x: Array, o: Array, m: Array,
           shuffle: Array, levy_shift: float) -> Array:
    """A hybrid function: z = M (x - o), shuffled, cut into groups, each group given to one
    basic function (unshifted, unrotated, scaled by its own rate), the values added."""
    n = x.shape[-1]
    z, _ = b.sr(x, o, m, 1.0)
    y = z[..., shuffle - 1]
    total = np.zeros(x.shape[:-1])
    start = 0
    for name, size in zip(parts, b.group_sizes(n, shares), strict=True):
        seg = y[..., start:start + size]
        if name == "schaffer_f7":  # reads the code's global y: the shuffled vector's head
            value = b.schaffer_f7(y[..., :size])
        elif name == "bi_rastrigin":
            value = b.bi_rastrigin(seg, o, None, shifted=False)
        else:
            zs, _ = b.sr(seg, None, None, b.RATE.get(name, 1.0))
            value = b.levy(zs, levy_shift) if name == "levy" else getattr(b, name)(zs)
        total = total + value
        start += size
    return total


@dataclass(frozen=True)
class Component:
    """One function of a composition: its part (a basic function name or a Hybrid), its
    rotation flag and its scale (value * numerator / denominator, as the code writes it)."""

    part: Any
    rotated: bool = True
    numerator: float = 1.0
    denominator: float = 1.0


@dataclass(frozen=True)
class Hybrid:
    parts: tuple[str, ...]
    shares: tuple[float, ...]


@dataclass(frozen=True)
class Composition:
    components: tuple[Component, ...]
    deltas: tuple[float, ...]
    biases: tuple[float, ...]


Definition = str | Hybrid | Composition


def evaluate(suite: str, f: int, definition: Definition, x: Array, bias: float,
             levy_shift: float) -> Array:
    n = x.shape[-1]
    o = _o(suite, f)
    if isinstance(definition, str):
        value = simple(definition, x, o[0], _m(suite, f, n)[0], levy_shift)
    elif isinstance(definition, Hybrid):
        value = hybrid(definition.parts, definition.shares, x, o[0], _m(suite, f, n)[0],
                       _s(suite, f, n)[0], levy_shift)
    else:
        value = _composition(suite, f, definition, x, o, levy_shift)
    return np.asarray(value + bias)


def _composition(suite: str, f: int, c: Composition, x: Array, o: Array,
                 levy_shift: float) -> Array:
    n = x.shape[-1]
    ms = _m(suite, f, n)
    fits = []
    for i, comp in enumerate(c.components):
        m = ms[i] if comp.rotated else None
        if isinstance(comp.part, Hybrid):
            assert comp.rotated
            v = hybrid(comp.part.parts, comp.part.shares, x, o[i], ms[i], _s(suite, f, n)[i],
                       levy_shift)
        else:
            v = simple(comp.part, x, o[i], m, levy_shift)
        v = comp.numerator * v / comp.denominator if comp.numerator != 1.0 else v
        fits.append(v + c.biases[i])
    weights = b.composition_weights(x, o, c.deltas)
    return b.sequential(weights * np.stack(fits, axis=-1))


# ------------------------------------------------------------------------ the two suites
def _c(part: Any, num: float = 1.0, den: float = 1.0, rotated: bool = True) -> Component:
    return Component(part, rotated, num, den)


_H17 = {
    11: Hybrid(("zakharov", "rosenbrock", "rastrigin"), (0.2, 0.4, 0.4)),
    12: Hybrid(("ellips", "schwefel", "bent_cigar"), (0.3, 0.3, 0.4)),
    13: Hybrid(("bent_cigar", "rosenbrock", "bi_rastrigin"), (0.3, 0.3, 0.4)),
    14: Hybrid(("ellips", "ackley", "schaffer_f7", "rastrigin"), (0.2, 0.2, 0.2, 0.4)),
    15: Hybrid(("bent_cigar", "hgbat", "rastrigin", "rosenbrock"), (0.2, 0.2, 0.3, 0.3)),
    16: Hybrid(("escaffer6", "hgbat", "rosenbrock", "schwefel"), (0.2, 0.2, 0.3, 0.3)),
    17: Hybrid(("katsuura", "ackley", "grie_rosen", "schwefel", "rastrigin"),
               (0.1, 0.2, 0.2, 0.2, 0.3)),
    18: Hybrid(("ellips", "ackley", "rastrigin", "hgbat", "discus"), (0.2,) * 5),
    19: Hybrid(("bent_cigar", "rastrigin", "grie_rosen", "weierstrass", "escaffer6"),
               (0.2,) * 5),
    20: Hybrid(("hgbat", "katsuura", "ackley", "rastrigin", "schwefel", "schaffer_f7"),
               (0.1, 0.1, 0.2, 0.2, 0.2, 0.2)),
}
_D3, _D4, _D5, _D6 = (10.0, 20.0, 30.0), (10.0, 20.0, 30.0, 40.0), (
    10.0, 20.0, 30.0, 40.0, 50.0), (10.0, 20.0, 30.0, 40.0, 50.0, 60.0)


def _bias(k: int) -> tuple[float, ...]:
    return tuple(100.0 * i for i in range(k))


CEC2017: dict[int, tuple[Definition, str]] = {
    1: ("bent_cigar", "shifted and rotated bent cigar"),
    2: ("sum_diff_pow", "shifted and rotated sum of different power (excluded by the "
        "organisers)"),
    3: ("zakharov", "shifted and rotated Zakharov"),
    4: ("rosenbrock", "shifted and rotated Rosenbrock"),
    5: ("rastrigin", "shifted and rotated Rastrigin"),
    6: ("schaffer_f7", "shifted and rotated expanded Schaffer F6 (the code: Schaffer F7, "
        "unrotated)"),
    7: ("bi_rastrigin", "shifted and rotated Lunacek bi-Rastrigin"),
    8: ("step_rastrigin", "shifted and rotated non-continuous Rastrigin (the code: Rastrigin)"),
    9: ("levy", "shifted and rotated Levy"),
    10: ("schwefel", "shifted and rotated Schwefel"),
    **{f: (h, f"hybrid function {f - 10}") for f, h in _H17.items()},
    21: (Composition((_c("rosenbrock"), _c("ellips", 10000, 1e10), _c("rastrigin")), _D3,
                     _bias(3)), "composition function 1"),
    22: (Composition((_c("rastrigin"), _c("griewank", 1000, 100), _c("schwefel")), _D3,
                     _bias(3)), "composition function 2"),
    23: (Composition((_c("rosenbrock"), _c("ackley", 1000, 100), _c("schwefel"),
                      _c("rastrigin")), _D4, _bias(4)), "composition function 3"),
    24: (Composition((_c("ackley", 1000, 100), _c("ellips", 10000, 1e10),
                      _c("griewank", 1000, 100), _c("rastrigin")), _D4, _bias(4)),
         "composition function 4"),
    25: (Composition((_c("rastrigin", 10000, 1e3), _c("happycat", 1000, 1e3),
                      _c("ackley", 1000, 100), _c("discus", 10000, 1e10), _c("rosenbrock")),
                     _D5, _bias(5)), "composition function 5"),
    26: (Composition((_c("escaffer6", 10000, 2e7), _c("schwefel"), _c("griewank", 1000, 100),
                      _c("rosenbrock"), _c("rastrigin", 10000, 1e3)),
                     (10.0, 20.0, 20.0, 30.0, 40.0), _bias(5)), "composition function 6"),
    27: (Composition((_c("hgbat", 10000, 1000), _c("rastrigin", 10000, 1e3),
                      _c("schwefel", 10000, 4e3), _c("bent_cigar", 10000, 1e30),
                      _c("ellips", 10000, 1e10), _c("escaffer6", 10000, 2e7)), _D6, _bias(6)),
         "composition function 7"),
    28: (Composition((_c("ackley", 1000, 100), _c("griewank", 1000, 100),
                      _c("discus", 10000, 1e10), _c("rosenbrock"), _c("happycat", 1000, 1e3),
                      _c("escaffer6", 10000, 2e7)), _D6, _bias(6)), "composition function 8"),
    29: (Composition((_c(_H17[15]), _c(_H17[16]), _c(_H17[17])), (10.0, 30.0, 50.0),
                     _bias(3)), "composition function 9"),
    30: (Composition((_c(_H17[15]), _c(_H17[18]), _c(_H17[19])), (10.0, 30.0, 50.0),
                     _bias(3)), "composition function 10"),
}

CEC2022: dict[int, tuple[Definition, str, float]] = {
    1: ("zakharov", "shifted and fully rotated Zakharov", 300.0),
    2: ("rosenbrock", "shifted and fully rotated Rosenbrock", 400.0),
    3: ("schaffer_f7", "shifted and fully rotated expanded Schaffer f6 (the code: Schaffer "
        "F7, unrotated)", 600.0),
    4: ("step_rastrigin", "shifted and fully rotated non-continuous Rastrigin (the code: "
        "Rastrigin)", 800.0),
    5: ("levy", "shifted and fully rotated Levy", 900.0),
    6: (Hybrid(("bent_cigar", "hgbat", "rastrigin"), (0.4, 0.4, 0.2)), "hybrid function 1",
        1800.0),
    7: (Hybrid(("hgbat", "katsuura", "ackley", "rastrigin", "schwefel", "schaffer_f7"),
               (0.1, 0.2, 0.2, 0.2, 0.1, 0.2)), "hybrid function 2", 2000.0),
    8: (Hybrid(("katsuura", "happycat", "grie_rosen", "schwefel", "ackley"),
               (0.3, 0.2, 0.2, 0.1, 0.2)), "hybrid function 3", 2200.0),
    9: (Composition((_c("rosenbrock", 10000, 1e4), _c("ellips", 10000, 1e10),
                     _c("bent_cigar", 10000, 1e30), _c("discus", 10000, 1e10),
                     _c("ellips", 10000, 1e10, rotated=False)), _D5,
                    (0.0, 200.0, 300.0, 100.0, 400.0)), "composition function 1", 2300.0),
    10: (Composition((_c("schwefel", rotated=False), _c("rastrigin"), _c("hgbat")),
                     (20.0, 10.0, 10.0), (0.0, 200.0, 100.0)), "composition function 2",
         2400.0),
    11: (Composition((_c("escaffer6", 10000, 2e7), _c("schwefel"), _c("griewank", 1000, 100),
                      _c("rosenbrock"), _c("rastrigin", 10000, 1e3)),
                     (20.0, 20.0, 30.0, 30.0, 20.0), (0.0, 200.0, 300.0, 400.0, 200.0)),
         "composition function 3", 2600.0),
    12: (Composition((_c("hgbat", 10000, 1000), _c("rastrigin", 10000, 1e3),
                      _c("schwefel", 10000, 4e3), _c("bent_cigar", 10000, 1e30),
                      _c("ellips", 10000, 1e10), _c("escaffer6", 10000, 2e7)), _D6,
                     (0.0, 300.0, 500.0, 100.0, 400.0, 200.0)), "composition function 4",
         2700.0),
}

DIMENSIONS = {"cec2017": (10, 30, 50, 100), "cec2022": (10, 20)}


def values(suite: str, f: int, X: Array, dim: int, instance: int) -> Array:
    """f(X) of ``suite`` F``f`` (the code's value, bias included) for X (..., dim)."""
    x = np.asarray(X, dtype=float)
    if suite == "cec2017":
        definition, _ = CEC2017[f]
        return evaluate(suite, f, definition, x, 100.0 * f, 1.0)
    definition, _, bias = CEC2022[f]
    return evaluate(suite, f, definition, x, bias, 0.0)


def optimum(suite: str, f: int, dim: int, instance: int) -> tuple[Array, float]:
    """(x_opt, f_opt): the first shift vector o, where every function's value is its bias,
    except CEC 2017 F9: the code's Levy is 0 at z = M (x - o) = 1, i.e. x = o + M^-1 1 (its
    M is not orthogonal); f_opt is the bias."""
    o = np.array(_o(suite, f)[0, :dim])
    if suite == "cec2017" and f == 9:
        o = o + np.linalg.solve(_m(suite, f, dim)[0], np.ones(dim))
    bias = 100.0 * f if suite == "cec2017" else CEC2022[f][2]
    return o, float(bias)
