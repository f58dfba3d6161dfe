"""The ``data`` array of a compiled CEC objective: the function's definition (the numpy suite's
tables, :data:`swarmpath.functions.suites.cec.CEC2017` / ``CEC2022``) and its official data,
packed for :mod:`.cec`, which interprets it. Constants the numpy suite computes with ``pow``
from the dimension are computed here by the same numpy expressions.

Layout (offsets are positions in the array, stored as floats; -1: none)::

    [0] length  [1] f_opt (the bias the code adds)  [2] 1 if a composition  [3] components k
    [4] Levy's shift  [5:8] unused
    k component records of RECORD numbers (below), then the blocks they point to.

A component record: [0] 1 if a hybrid, [1] offset of o (D), [2] offset of M (D, D) or -1
(not rotated), [3] offset of its applications, [4] their count, [5] offset of the hybrid's
shuffle (D, 0-based), [6] 1 if scaled, [7] numerator, [8] denominator, [9] the composition's
bias, [10] delta ** 2. An application of a basic function (APPLICATION numbers): its code
(:data:`CODES`), its dimension n, its scale (the code's sh_rate), the offset of its constants
(or -1). A plain function is one component with one application; a hybrid one component with
an application per group; a composition one component per function.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarmpath.functions.suites import cec
from swarmpath.functions.suites import cec_basic as b

HEADER = 8
RECORD = 12
APPLICATION = 4

#: basic function -> code (step_rastrigin is Rastrigin in the code, see the numpy suite)
CODES = {name: k for k, name in enumerate((
    "bent_cigar", "sum_diff_pow", "zakharov", "rosenbrock", "rastrigin", "schaffer_f7",
    "bi_rastrigin", "levy", "schwefel", "ellips", "discus", "ackley", "weierstrass",
    "griewank", "katsuura", "grie_rosen", "escaffer6", "happycat", "hgbat"))}
CODES["step_rastrigin"] = CODES["rastrigin"]


def constants(name: str, n: int) -> np.ndarray | None:
    """The constants basic function ``name`` reads in n dimensions, as the numpy suite
    computes them (None: it reads none)."""
    if name == "ellips":
        return np.asarray(10.0 ** (6.0 * np.arange(n, dtype=float) / (n - 1)))
    if name == "bi_rastrigin":
        mu0, d = 2.5, 1.0
        s = 1.0 - 1.0 / (2.0 * (n + 20.0) ** 0.5 - 8.2)
        return np.array([s, -(((mu0 * mu0 - d) / s) ** 0.5)])
    if name == "katsuura":
        return np.concatenate([[10.0 / (1.0 * n) ** 1.2, 10.0 / n / n],
                               2.0 ** np.arange(1, 33)])
    if name == "weierstrass":
        return np.concatenate([b._WA, 2.0 * b.PI * b._WB, [b._W_AT_HALF]])
    return None


class _Packer:
    def __init__(self, head: int) -> None:
        self.head = np.full(head, -1.0)
        self.blocks: list[np.ndarray] = []
        self.size = head

    def put(self, values: Any) -> int:
        block = np.ascontiguousarray(values, dtype=np.float64).ravel()
        at = self.size
        self.blocks.append(block)
        self.size += block.size
        return at

    def applications(self, parts: list[tuple[str, int]]) -> int:
        table = np.zeros((len(parts), APPLICATION))
        for row, (name, n) in zip(table, parts, strict=True):
            aux = constants(name, n)
            row[:] = CODES[name], n, b.RATE.get(name, 1.0), -1 if aux is None else self.put(aux)
        return self.put(table)


def _definition(suite: str, f: int) -> tuple[cec.Definition, float, float]:
    """(definition, bias, Levy's shift) as ``cec.values`` reads them."""
    if suite == "cec2017":
        return cec.CEC2017[f][0], 100.0 * f, 1.0
    definition, _, bias = cec.CEC2022[f]
    return definition, bias, 0.0


def pack(suite: str, f: int, dim: int) -> np.ndarray:
    """The ``data`` array of ``suite`` F``f`` in ``dim`` dimensions."""
    definition, bias, levy_shift = _definition(suite, f)
    o, ms = cec._o(suite, f), cec._m(suite, f, dim)
    if isinstance(definition, cec.Composition):
        parts = [(c.part, c.rotated, c.numerator, c.denominator) for c in definition.components]
        biases, deltas = definition.biases, definition.deltas
    else:
        parts = [(definition, True, 1.0, 1.0)]
        biases, deltas = (0.0,), (1.0,)
    k = len(parts)
    packer = _Packer(HEADER + k * RECORD)
    head = packer.head
    head[1:5] = bias, float(isinstance(definition, cec.Composition)), k, levy_shift
    for i, (part, rotated, numerator, denominator) in enumerate(parts):
        record = head[HEADER + i * RECORD:HEADER + (i + 1) * RECORD]
        record[0] = float(isinstance(part, cec.Hybrid))
        record[1] = packer.put(o[i, :dim])
        record[2] = packer.put(ms[i]) if rotated else -1.0
        if isinstance(part, cec.Hybrid):
            sizes = b.group_sizes(dim, part.shares)
            record[3] = packer.applications(list(zip(part.parts, sizes, strict=True)))
            record[4] = len(sizes)
            record[5] = packer.put(cec._s(suite, f, dim)[i] - 1)
        else:
            record[3] = packer.applications([(part, dim)])
            record[4] = 1
        record[6:11] = (float(numerator != 1.0), numerator, denominator, biases[i],
                        deltas[i] ** 2.0)
    out = np.concatenate([head, *packer.blocks])
    out[0] = out.size
    return out


def data_for(fn: Any, dim: int) -> np.ndarray:
    """:func:`pack` for a registered ``cec2017:F<k>`` / ``cec2022:F<k>`` function."""
    return pack(str(fn.suite), int(fn.number), int(dim))
