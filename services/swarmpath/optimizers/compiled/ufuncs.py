"""numpy's own inner loops, called from compiled code: the same numbers as numpy, by construction.

numpy picks several of its float64 loops at run time by CPU, and they are not the C library's:
on this machine (AVX-512) ``np.cbrt`` differs from libm's cbrt in the last bit for about half of
the arguments, and ``np.matmul`` sums through OpenBLAS, whose kernels add a row's products in
an order that depends on the shape (index order at 30 x 30, another order for the last columns
when the number of columns is 1-4 past a multiple of 8). Compiled code that must give the
reference's numbers bit for bit calls numpy's loop itself: :func:`numpy_loop` reads it from the
ufunc object (``PyUFuncObject`` of numpy's public C API: ``functions``, ``data``, ``ntypes``,
``types``), and :func:`link` binds it to a symbol name that compiled code calls like a C
function, with numpy's loop convention (``args``, ``dimensions``, ``steps``, ``data``):
:func:`exp_inplace`, :func:`cbrt_inplace`, :func:`matmul_into`, :func:`power`. A call by name
keeps the callers cacheable (a ctypes function as a global would not) and needs no argument
threaded through a kernel.
"""

from __future__ import annotations

import ctypes
from typing import Any

import llvmlite.binding as llvm
import numpy as np
from llvmlite import ir
from numba import njit
from numba import types as nbtypes
from numba.core import cgutils
from numba.extending import intrinsic

from swarmpath.optimizers.compiled.norefcount import NO_REFCOUNT

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
_call_cbrt = _linked_loop("swarmpath_numpy_cbrt_dd", np.cbrt, "dd")
_call_cos = _linked_loop("swarmpath_numpy_cos_dd", np.cos, "dd")
_call_sin = _linked_loop("swarmpath_numpy_sin_dd", np.sin, "dd")
_call_log1p = _linked_loop("swarmpath_numpy_log1p_dd", np.log1p, "dd")
_call_matmul = _linked_loop("swarmpath_numpy_matmul_ddd", np.matmul, "ddd")


@njit(cache=True, **NO_REFCOUNT)
def _in_place(x, call):
    """numpy's loop arguments (args, dimensions, steps) for x = f(x), x contiguous float64, in
    ``call`` (int64, 5): the addresses of the three arrays."""
    call[0] = x.ctypes.data
    call[1] = x.ctypes.data
    call[2] = x.size
    call[3] = 8
    call[4] = 8
    return call.ctypes.data, call[2:].ctypes.data, call[3:].ctypes.data


# x = f(x) in place for a contiguous float64 x with numpy's own loop (on AVX-512 not the C
# library's: exp, cos, sin and log1p differ from it in the last bit for about one argument in a
# hundred, cbrt for about half); ``call`` is int64 scratch (5,).
@njit(cache=True, **NO_REFCOUNT)
def exp_inplace(x, call):
    _call_exp(*_in_place(x, call))


@njit(cache=True, **NO_REFCOUNT)
def cbrt_inplace(x, call):
    _call_cbrt(*_in_place(x, call))


@njit(cache=True, **NO_REFCOUNT)
def cos_inplace(x, call):
    _call_cos(*_in_place(x, call))


@njit(cache=True, **NO_REFCOUNT)
def sin_inplace(x, call):
    _call_sin(*_in_place(x, call))


@njit(cache=True, **NO_REFCOUNT)
def log1p_inplace(x, call):
    _call_log1p(*_in_place(x, call))


@njit(cache=True, **NO_REFCOUNT)
def matmul_into(A, B, C, call):
    """C = A @ B (float64 matrices, any strides) with numpy's matmul loop, as one item of
    ``np.matmul``'s outer loop (its BLAS call, so its order of additions); ``call`` is int64
    scratch (16,)."""
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
    _call_matmul(call.ctypes.data, call[3:].ctypes.data, call[7:].ctypes.data)


@njit(cache=True, **NO_REFCOUNT)
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
