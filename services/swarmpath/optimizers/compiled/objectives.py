"""Benchmark functions as compiled population objectives, called by the kernels through a pointer.

A population objective is a C function (numba ``cfunc``, cached) with the signature
:data:`SIGNATURE`::

    void objective(int64 m, int64 d, double *X, double *F, uint8 *mask, double *work,
                   double *data)

It writes the value of each row of the contiguous population X (m, d) whose ``mask`` byte is
not 0 to F (m,) and +inf to the others; ``work`` is scratch of at least 3 d + 2 m doubles,
``data`` the function's own constants (a float64 array, empty for F1-F13). A kernel calls it
through :func:`evaluate`, which adds what ``BenchmarkProblem._evaluate`` and
``Optimizer.evaluate`` add around the function: the run's shift (F8 then wrapped into its box),
F7's noise drawn from the run's stream, NaN as +inf.

Why a pointer: the kernels do not contain the functions' code. A kernel is compiled once for
every function (before: each kernel inlined all fourteen, which made it 10-20 s of LLVM work
and put a branch on the function id in front of every point), a function is compiled only when
a study uses it, and the code of the point loop is the function's alone (fixed at compile time,
as in a hand-written loop). It is also the extension point: :func:`register_population`
adds the compiled objective of another registered function (its ``data`` carries what it
needs: shifts, matrices), and every kernel runs it.

The objective a kernel receives is the tuple ``(address, noisy, wrapped, data address)`` made by
:func:`objective_for`.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from typing import Any

import numpy as np
from llvmlite import ir
from numba import carray, cfunc, njit, types
from numba.extending import intrinsic

from swarmpath.functions import BenchmarkFunction, get_function, list_functions
from swarmpath.optimizers.compiled.functions import (
    ackley_parts,
    griewank,
    penalized_1,
    penalized_2,
    quartic,
    rastrigin,
    rosenbrock,
    schwefel_1_2,
    schwefel_2_21,
    schwefel_2_22,
    schwefel_2_26,
    sphere,
    step,
    step_floor,
)
from swarmpath.optimizers.compiled.norefcount import NO_REFCOUNT
from swarmpath.optimizers.compiled.streams import RANDOM, take
from swarmpath.optimizers.compiled.ufuncs import exp_inplace

_E = float(np.e)
_P = types.CPointer(types.float64)
SIGNATURE = types.void(types.int64, types.int64, _P, _P, types.CPointer(types.uint8), _P, _P)

Objective = tuple[int, bool, bool, int]
DataOf = Callable[[BenchmarkFunction, int], np.ndarray]


@njit(cache=True)
def _views(m, d, xp, fp, mp, wp):
    return carray(xp, (m, d)), carray(fp, m), carray(mp, m), carray(wp, (3, d))


# One population function per point function: the point function is fixed at compile time.
def _f1(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = sphere(X[i], w) if mask[i] else np.inf


def _f2(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = schwefel_2_22(X[i], w) if mask[i] else np.inf


def _f3(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = schwefel_1_2(X[i], w) if mask[i] else np.inf


def _f4(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = schwefel_2_21(X[i], w) if mask[i] else np.inf


def _f5(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = rosenbrock(X[i], w) if mask[i] else np.inf


def _f6(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = step(X[i], w) if mask[i] else np.inf


def _f6_floor(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = step_floor(X[i], w) if mask[i] else np.inf


def _f7(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = quartic(X[i], w) if mask[i] else np.inf


def _f8(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = schwefel_2_26(X[i], w) if mask[i] else np.inf


def _f9(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = rastrigin(X[i], w) if mask[i] else np.inf


def _f10(m, d, xp, fp, mp, wp, dp):
    """Ackley: the exponent arguments of every row computed, then numpy's exp loop on all of
    them at once (:func:`ufuncs.exp_inplace`: numpy's vectorised exp differs from the C
    library's in the last bit for about one argument in a hundred)."""
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    e = carray(wp, 3 * d + 2 * m)[3 * d:]
    for i in range(m):
        if mask[i]:
            e[i], e[m + i] = ackley_parts(X[i], w)
        else:
            e[i] = 0.0
            e[m + i] = 0.0
    exp_inplace(e, np.empty(5, dtype=np.int64))
    for i in range(m):
        F[i] = ((-20.0 * e[i] - e[m + i]) + 20.0) + _E if mask[i] else np.inf


def _f11(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = griewank(X[i], w) if mask[i] else np.inf


def _f12(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = penalized_1(X[i], w) if mask[i] else np.inf


def _f13(m, d, xp, fp, mp, wp, dp):
    X, F, mask, w = _views(m, d, xp, fp, mp, wp)
    for i in range(m):
        F[i] = penalized_2(X[i], w) if mask[i] else np.inf


#: Population functions (plain functions with :data:`SIGNATURE`'s parameters), by registered
#: function name; compiled on first use.
_POPULATIONS: dict[str, Callable[..., None]] = {
    "F1": _f1, "F2": _f2, "F3": _f3, "F4": _f4, "F5": _f5, "F6": _f6, "F6-floor": _f6_floor,
    "F7": _f7, "F8": _f8, "F9": _f9, "F10": _f10, "F11": _f11, "F12": _f12, "F13": _f13,
}
# Every built-in function has a compiled objective; suites' and plugins' register theirs.
assert set(_POPULATIONS) == set(list_functions(builtin=True)), "a built-in has no objective"
_COMPILED: dict[Callable[..., None], Any] = {}
_NO_DATA = np.empty(0)
_KEPT: dict[tuple[str, bytes], np.ndarray] = {}  # the data arrays objectives point to
_DATA_OF: dict[str, DataOf] = {}


def register_population(name: str, population: Callable[..., None],
                        data: DataOf | None = None) -> None:
    """Make ``population`` (a module-level function with :data:`SIGNATURE`'s parameters, not
    yet compiled) the compiled objective of the registered function ``name``; ``data(fn, dim)``
    gives the constants it reads (an instance's optimum, rotations, ...) for ``fn`` (``name``
    or, for a suite function, one of its instances) in ``dim`` dimensions."""
    get_function(name)  # KeyError naming it if there is no such function
    if _POPULATIONS.get(name, population) is not population:
        raise ValueError(f"function {name!r} has a compiled objective already")
    _POPULATIONS[name] = population
    if data is not None:
        _DATA_OF[name] = data


def compiled_names() -> list[str]:
    """Registered functions with a compiled objective."""
    _register_suites()
    return [name for name in _POPULATIONS]


def _population_name(fn: BenchmarkFunction) -> str:
    """The name ``fn``'s objective is registered under: its own, or for an instance of a suite
    function its base name (``bbob:f3@i7`` -> ``bbob:f3``; see ``SuiteFunction``)."""
    return str(getattr(fn, "objective_name", fn.name))


def has_objective(fn: BenchmarkFunction) -> bool:
    """Whether ``fn`` (a registered function, not a hand-made one of the same name) has a
    compiled objective."""
    _register_suites()
    try:
        registered = get_function(fn.name)
    except KeyError:
        return False
    # an instance of a suite function is a new object per lookup: its kernel compares equal
    return _population_name(fn) in _POPULATIONS and (
        fn.kernel is registered.kernel or fn.kernel == registered.kernel)


def data_for(fn: BenchmarkFunction, dim: int) -> np.ndarray:
    """The ``data`` array of ``fn``'s objective in ``dim`` dimensions (empty: none needed)."""
    _register_suites()
    data_of = _DATA_OF.get(_population_name(fn))
    return _NO_DATA if data_of is None else data_of(fn, dim)


def objective_for(fn: BenchmarkFunction, data: np.ndarray = _NO_DATA) -> Objective:
    """The tuple a kernel takes for ``fn``: (its compiled objective's address, noisy, wrapped
    when shifted, the address of ``data`` (:func:`data_for`), which is kept alive here: once
    per distinct content); compiles (or loads from numba's cache) the objective on first use.
    KeyError if ``fn`` has none (:func:`has_objective`)."""
    compiled = _compiled(fn)
    constants = np.ascontiguousarray(data, dtype=np.float64)
    constants = _KEPT.setdefault((fn.name, constants.tobytes()), constants)
    return (int(compiled.address), bool(fn.noisy), bool(fn.wrap_shifted),
            int(constants.ctypes.data))


def _compiled(fn: BenchmarkFunction) -> Any:
    """``fn``'s compiled objective (the cfunc), compiled or loaded on first use."""
    if not has_objective(fn):
        raise KeyError(fn.name)
    population = _POPULATIONS[_population_name(fn)]
    compiled: Any = _COMPILED.get(population)
    if compiled is None:  # once per population function (the CEC functions share one)
        compiled = _COMPILED[population] = cfunc(SIGNATURE, cache=True)(population)
    return compiled


_CALLABLE = ctypes.CFUNCTYPE(None, ctypes.c_int64, ctypes.c_int64, *[ctypes.c_void_p] * 5)


def population_values(fn: BenchmarkFunction, X: np.ndarray) -> np.ndarray:
    """The values ``fn``'s compiled objective gives the rows of X (m, d), called from Python
    (tests and benchmarks compare them with the numpy kernel's): no shift, noise or NaN rule,
    which :func:`evaluate` adds around it."""
    X = np.ascontiguousarray(X, dtype=np.float64)
    m, d = X.shape
    data = np.ascontiguousarray(data_for(fn, d), dtype=np.float64)
    call = _CALLABLE(_compiled(fn).address)
    F = np.empty(m)
    mask = np.ones(m, dtype=np.uint8)
    work = np.empty(m * d + 3 * d + 2 * m)
    call(m, d, X.ctypes.data, F.ctypes.data, mask.ctypes.data, work.ctypes.data,
         data.ctypes.data)
    return F


_SUITES_REGISTERED = False


def _register_suites() -> None:
    """The suites' compiled objectives (on first need: importing them loads the suites)."""
    global _SUITES_REGISTERED
    if _SUITES_REGISTERED:
        return
    _SUITES_REGISTERED = True
    from swarmpath.optimizers.compiled import bbob, cec

    for suite in (bbob, cec):
        for name, population in suite.POPULATIONS.items():
            register_population(name, population, suite.data_for)


def _typed_call(typingctx, address, X, x_at, d, F, row, m, mask, work, w_at, data):
    """address(m, d, X + x_at, F + row, mask + row, work + w_at, data) for contiguous arrays
    (``x_at`` and ``w_at`` count numbers, ``row`` elements) and ``data`` an address: m points of
    d coordinates from X's number ``x_at``, their values at F[row:row + m]. Pointers, not
    views: a view costs reference counting, a quarter of an HPO run that evaluates one agent at
    a time."""
    signature = types.void(address, X, x_at, d, F, row, m, mask, work, w_at, data)

    def codegen(context, builder, sig, args):
        i64 = ir.IntType(64)
        double = ir.DoubleType().as_pointer()
        byte = ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [i64, i64, double, double, byte, double, double])
        fn = builder.inttoptr(args[0], fnty.as_pointer())
        data = {k: context.make_array(sig.args[k])(context, builder, args[k]).data
                for k in (1, 4, 7, 8)}
        x_at, d, row, m, w_at = (context.cast(builder, args[k], sig.args[k], types.int64)
                                 for k in (2, 3, 5, 6, 9))
        x = builder.gep(builder.bitcast(data[1], double), [x_at])
        f = builder.gep(builder.bitcast(data[4], double), [row])
        mask = builder.gep(builder.bitcast(data[7], byte), [row])
        work = builder.gep(builder.bitcast(data[8], double), [w_at])
        constants = builder.inttoptr(context.cast(builder, args[10], sig.args[10], types.int64),
                                     double)
        builder.call(fn, [m, d, x, f, mask, work, constants])
        return context.get_dummy_value()

    return signature, codegen


_call: Any = intrinsic(_typed_call)


@njit(cache=True)
def work_for(m, d):
    """Scratch for :func:`evaluate` with populations of up to m points of d coordinates."""
    return np.empty(m * d + 3 * d + 2 * m)


@njit(cache=True, **NO_REFCOUNT)
def evaluate_rows(stream, objective, shifted, shift, lower, upper, X, start, stop, F, mask,
                  work):
    """Values of the rows [start, stop) of the population X into F[start:stop], as the
    reference's objective computes them.

    ``objective``: :func:`objective_for`'s tuple. ``shifted``: subtract ``shift`` (d,) first
    (a wrapped function is then wrapped into its box ``lower``, ``upper``). ``mask`` (bool,
    like F): False rows are not computed (F gets +inf), what the reference's masked evaluation
    leaves of them; the noise of a noisy function is drawn for all the rows either way.
    ``work``: :func:`work_for` (stop - start, d) or larger. NaN values become +inf, as
    ``Optimizer.evaluate`` does.
    """
    address, noisy, wrapped, data = objective
    m = stop - start
    d = X.shape[1]
    if shifted:
        for i in range(m):
            for j in range(d):
                z = X[start + i, j] - shift[j]
                if wrapped:
                    z = ((z - lower[j]) % (upper[j] - lower[j])) + lower[j]
                work[i * d + j] = z
        _call(address, work, 0, d, F, start, m, mask, work, m * d, data)
    else:
        _call(address, X, start * d, d, F, start, m, mask, work, m * d, data)
    if noisy:
        o = take(stream, RANDOM, m)
        row = stream[1][RANDOM]
        for i in range(m):
            F[start + i] = F[start + i] + row[o + i]
    for i in range(start, stop):
        if np.isnan(F[i]):
            F[i] = np.inf


@njit(cache=True, **NO_REFCOUNT)
def evaluate(stream, objective, shifted, shift, lower, upper, X, F, mask, work):
    """:func:`evaluate_rows` of the whole population X (m, d) into F (m,)."""
    evaluate_rows(stream, objective, shifted, shift, lower, upper, X, 0, X.shape[0], F, mask,
                  work)
