"""numpy's own inner loops, called from compiled code: the same numbers as numpy, by construction.

numpy picks several of its float64 loops at run time by CPU, and they are not the C library's:
on this machine (AVX-512) ``np.cbrt`` differs from libm's cbrt in the last bit for about half of
the arguments, and ``np.matmul`` sums through OpenBLAS, whose kernels add a row's products in
an order that depends on the shape (index order at 30 x 30, another order for the last columns
when the number of columns is 1-4 past a multiple of 8). Compiled code that must give the
reference's numbers bit for bit calls numpy's loop itself: :func:`numpy_loop` reads it from the
ufunc object (``PyUFuncObject`` of numpy's public C API: ``functions``, ``data``, ``ntypes``,
``types``), and :func:`unary` and :func:`matmul` call it with numpy's loop convention
(``args``, ``dimensions``, ``steps``, ``data``). The loop is passed to compiled functions as an
argument (a ctypes function): as a global it would keep numba from caching them. :func:`link`
instead binds a loop to a symbol name that compiled code calls like a C function (:func:`power`):
cacheable, and no argument to thread through a kernel.
"""

from __future__ import annotations

import ctypes
import types
from typing import Any

import llvmlite.binding as llvm
import numpy as np
from llvmlite import ir
from numba import njit
from numba import types as nbtypes
from numba.core import cgutils
from numba.extending import intrinsic

# PyUFuncObject (numpy/ufuncobject.h): PyObject_HEAD (16 bytes), int nin, nout, nargs,
# identity; PyUFuncGenericFunction *functions; void **data; int ntypes, reserved1;
# const char *name; char *types.
_FUNCTIONS = 32
_DATA = 40
_NTYPES = 48
_NAME = 56
_TYPES = 64

_P = ctypes.c_void_p
#: numpy's loop type: void loop(char **args, npy_intp *dimensions, npy_intp *steps, void *data)
LoopType = ctypes.CFUNCTYPE(None, _P, _P, _P, _P)
Loop = tuple[Any, int]  # (ctypes function, data pointer)


def _pointer(address: int) -> int:
    return ctypes.c_void_p.from_address(address).value or 0


def numpy_loop(ufunc: np.ufunc, types: str) -> Loop:
    """(loop, data) numpy runs for ``ufunc`` on the dtype characters ``types`` ('dd', 'ddd').

    RuntimeError if the object does not have the expected layout or has no such loop.
    """
    base = id(ufunc)
    if ctypes.string_at(_pointer(base + _NAME)) != ufunc.__name__.encode():
        raise RuntimeError(f"numpy's ufunc layout is not the expected one ({ufunc.__name__})")
    nargs = ufunc.nargs
    if len(types) != nargs:
        raise RuntimeError(f"{ufunc.__name__} takes {nargs} types, got {types!r}")
    ntypes = ctypes.c_int.from_address(base + _NTYPES).value
    if ntypes != len(ufunc.types):
        raise RuntimeError(f"numpy's ufunc layout is not the expected one ({ufunc.__name__})")
    table = ctypes.string_at(_pointer(base + _TYPES), nargs * ntypes)
    codes = bytes(np.dtype(c).num for c in types)
    for i in range(ntypes):
        if table[nargs * i : nargs * (i + 1)] == codes:
            loop = _pointer(_pointer(base + _FUNCTIONS) + 8 * i)
            return LoopType(loop), _pointer(_pointer(base + _DATA) + 8 * i)
    raise RuntimeError(f"numpy's {ufunc.__name__} has no {types} loop")


CBRT = numpy_loop(np.cbrt, "dd")
MATMUL = numpy_loop(np.matmul, "ddd")


@njit(cache=True)
def unary(loop, data, x, call):
    """x = ufunc(x) in place for a contiguous float64 x; ``call`` is int64 scratch (5,)."""
    call[0] = x.ctypes.data
    call[1] = x.ctypes.data
    call[2] = x.size
    call[3] = 8
    call[4] = 8
    loop(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data, data)


@njit(cache=True)
def matmul(loop, data, A, B, C, call):
    """C = A @ B (float64 matrices, any strides) with numpy's matmul loop, as one item of
    ``np.matmul``'s outer loop; ``call`` is int64 scratch (16,)."""
    call[0] = A.ctypes.data
    call[1] = B.ctypes.data
    call[2] = C.ctypes.data
    call[3] = 1  # outer loop length, then the core dimensions n, k, m
    call[4] = A.shape[0]
    call[5] = A.shape[1]
    call[6] = B.shape[1]
    call[7] = 0  # outer steps
    call[8] = 0
    call[9] = 0
    call[10] = A.strides[0]
    call[11] = A.strides[1]
    call[12] = B.strides[0]
    call[13] = B.strides[1]
    call[14] = C.strides[0]
    call[15] = C.strides[1]
    loop(call.ctypes.data, call[3:].ctypes.data, call[7:].ctypes.data, data)


def link(symbol: str, ufunc: np.ufunc, types: str) -> None:
    """Make numpy's loop for ``ufunc`` on ``types`` callable from compiled code by the name
    ``symbol`` (see :func:`power`). A call by name, unlike a function pointer argument, keeps
    the callers cacheable; the name is bound again in every process, at import."""
    loop, data = numpy_loop(ufunc, types)
    if data:
        raise RuntimeError(f"numpy's {ufunc.__name__} loop needs its data pointer")
    llvm.add_symbol(symbol, ctypes.cast(loop, ctypes.c_void_p).value)


def _linked_loop(symbol: str, ufunc: np.ufunc, types: str) -> Any:
    """An intrinsic calling numpy's loop ``symbol``(args, dimensions, steps, NULL), the three
    arrays given by address (int64)."""
    link(symbol, ufunc, types)

    @intrinsic
    def call(typingctx, args, dimensions, steps):
        signature = nbtypes.void(nbtypes.int64, nbtypes.int64, nbtypes.int64)

        def codegen(context, builder, sig, values):
            pointer = ir.IntType(8).as_pointer()
            fnty = ir.FunctionType(ir.VoidType(), [pointer] * 4)
            fn = cgutils.get_or_insert_function(builder.module, fnty, symbol)
            operands = [builder.inttoptr(v, pointer) for v in values]
            builder.call(fn, [*operands, ir.Constant(pointer, None)])
            return context.get_dummy_value()

        return signature, codegen

    return call


_call_power = _linked_loop("swarmpath_numpy_power_ddd", np.power, "ddd")
_call_exp = _linked_loop("swarmpath_numpy_exp_dd", np.exp, "dd")


@njit(cache=True)
def exp_inplace(x, call):
    """x = np.exp(x) in place for a contiguous float64 x, with numpy's own loop (on AVX-512 not
    the C library's exp); ``call`` is int64 scratch (5,)."""
    call[0] = x.ctypes.data
    call[1] = x.ctypes.data
    call[2] = x.size
    call[3] = 8
    call[4] = 8
    _call_exp(call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data)


@njit(cache=True)
def power(x, e, call):
    """``x ** e`` for float64 numbers as numpy computes an array to a scalar power (the
    exponent's stride 0: numpy's loop takes its x * x, 1 / x, sqrt(x) shortcuts for e = 2, -1,
    0.5, and otherwise, on AVX-512, SVML's pow, not the C library's); ``call`` is int64
    scratch (10,), its last three entries the operands and the result."""
    values = call[7:].view(np.float64)
    values[0] = x
    values[1] = e
    base = values.ctypes.data
    call[0] = base
    call[1] = base + 8
    call[2] = base + 16
    call[3] = 1  # one element, the exponent a broadcast scalar
    call[4] = 8
    call[5] = 0
    call[6] = 8
    _call_power(call.ctypes.data, call[3:].ctypes.data, call[4:].ctypes.data)
    return values[2]


_FUSED: dict[tuple[Any, Any], Any] = {}


def with_objective(kernel: Any, evaluate: Any) -> Any:
    """The @njit ``kernel`` compiled again with its global ``evaluate`` bound to ``evaluate``
    (not cached): the benchmark's fused loop. A kernel whose objective is a function argument
    instead could not be cached together with numpy's loops (numba: "dynamic globals")."""
    key = (kernel, evaluate)
    if key not in _FUSED:
        source = kernel.py_func
        scope = dict(source.__globals__, evaluate=evaluate)
        _FUSED[key] = njit(types.FunctionType(source.__code__, scope, source.__name__))
    return _FUSED[key]
