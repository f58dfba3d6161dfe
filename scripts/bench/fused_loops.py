"""The independent fused loops of ``scripts/bench/kernels.py``, by algorithm name: each value
makes the algorithm's loop for one objective (``fused_common.OBJECTIVES``)."""

from __future__ import annotations

from fused_bats import make_ba, make_bats
from fused_classic import make_fdo, make_gwo, make_pso, make_ssa
from fused_coot import COOT, ICOOT, MCOOT, make_coot
from fused_hpo import make_hpo, make_rfo

LOOPS = {
    "PSO": make_pso,
    "GWO": make_gwo,
    "SSA": make_ssa,
    "FDO": make_fdo,
    "COOT": lambda objective: make_coot(objective, COOT),
    "mCOOT": lambda objective: make_coot(objective, MCOOT),
    "ICOOT": lambda objective: make_coot(objective, ICOOT),
    "HPO": lambda objective: make_hpo(objective, False),
    "IHPO": lambda objective: make_hpo(objective, True),
    "RFO": make_rfo,
    "BA": make_ba,
    "MFB": lambda objective: make_bats(objective, False),
    "HPSO-MFB": lambda objective: make_bats(objective, True),
}
