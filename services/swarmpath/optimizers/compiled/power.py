"""numpy's float64 ``x ** e`` as a compiled scalar function, to the last bit.

numpy computes ``x ** e`` on float64 arrays as x * x for e = 2, 1 / x for e = -1, sqrt(x) for
e = 0.5, and otherwise, where its runtime dispatches to AVX512_SKX, with the high-accuracy SVML
routine ``__svml_pow8_ha`` that numpy links into its umath module (elsewhere with the C
library's ``pow``). The SVML result differs from the C library's in the last bit for about 5% of
arguments, enough to move an algorithm's trajectory (ICOOT's density, ``icoot.py``). ``power``
here calls the same routine numpy calls: lane 0 of an 8-lane call, the other lanes 1.
"""

from __future__ import annotations

import ctypes
import importlib
import math

import llvmlite.binding as llvm
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

_SVML_NAME = "__svml_pow8_ha"
_umath = importlib.import_module("numpy._core._multiarray_umath")


def _register_svml() -> bool:
    """Make numpy's SVML pow known to the compiler (always when numpy has it: code compiled
    and cached with it must link), and say whether numpy's power uses it on this machine."""
    try:
        symbol = getattr(ctypes.CDLL(_umath.__file__), _SVML_NAME)
    except (OSError, AttributeError):
        return False
    llvm.add_symbol(_SVML_NAME, ctypes.cast(symbol, ctypes.c_void_p).value)
    return bool(_umath.__cpu_features__.get("AVX512_SKX", False))


#: True when numpy's power runs SVML here (the compiled ``power`` then calls it too).
SVML = _register_svml()


@intrinsic
def _svml_pow(typingctx, x, y):
    signature = types.float64(types.float64, types.float64)

    def codegen(context, builder, sig, args):
        lanes = ir.VectorType(ir.DoubleType(), 8)
        fnty = ir.FunctionType(lanes, [lanes, lanes])
        fn = builder.module.globals.get(_SVML_NAME) or ir.Function(builder.module, fnty,
                                                                   _SVML_NAME)
        ones = ir.Constant(lanes, [1.0] * 8)
        lane0 = ir.Constant(ir.IntType(32), 0)
        a = builder.insert_element(ones, args[0], lane0)
        b = builder.insert_element(ones, args[1], lane0)
        return builder.extract_element(builder.call(fn, [a, b]), lane0)

    return signature, codegen


if SVML:

    @njit(cache=False)
    def _general(x: float, e: float) -> float:
        return _svml_pow(x, e)  # type: ignore[call-arg]

else:

    @njit(cache=False)
    def _general(x: float, e: float) -> float:
        return math.pow(x, e)


@njit(cache=False)
def power(x: float, e: float) -> float:
    """``x ** e`` as numpy computes it for float64 arrays (see the module docstring)."""
    if e == 2.0:
        return x * x
    if e == -1.0:
        return 1.0 / x
    if e == 0.5:
        return math.sqrt(x)
    return _general(x, e)
