"""Raced benchmark jobs: the ``racing`` field of a job spec and the blocks its cells race in.

A raced job is stored like any other, except that a cell's ``runs`` column is its current
allowance (what may be leased now) rather than the job's ``runs``: it starts at ``min_runs`` and
the store raises it round by round (:mod:`swarmpath.service.store.races`) from the decisions of
:func:`swarmpath.evidence.racing.race_block`. The job's ``runs`` is the largest number of runs a
cell may get (``max_runs``), so run r of cell c keeps its id ``c * runs + r`` and its numbers
whether the race reaches it or not.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import Field, field_validator, model_validator

from swarmpath.evidence.racing import (
    EVERY_ROUND,
    PAIRS,
    SEQUENCE_SHARE,
    RaceSettings,
    comparisons_per_block,
    default_design,
)
from swarmpath.service.model import MAX_RUNS_PER_CELL, Model

#: Cell spec fields that tell the algorithms of a block apart (the rest is the block): with an
#: evaluation budget each algorithm has its own iterations (those spending the budget).
_MEMBER_FIELDS = ("algorithm", "params", "iterations")


class RacingSpec(Model):
    """``racing`` in a benchmark job spec. ``max_runs`` is the job's ``runs`` (it may be left
    out); ``margin`` is on the scale of the probability that one algorithm's run beats the
    other's (0.5 +- margin counts as equivalent; 0: only differences stop a comparison)."""

    alpha: float = Field(default=0.05, gt=0, lt=1, allow_inf_nan=False,
                         description="error rate of the whole study's race decisions")
    min_runs: int = Field(default=10, ge=1, le=MAX_RUNS_PER_CELL, strict=True,
                          description="runs every cell gets before its first decision")
    max_runs: int | None = Field(default=None, ge=1, le=MAX_RUNS_PER_CELL, strict=True,
                                 description="the job's runs (the most a cell may get)")
    batch: int = Field(default=10, ge=1, le=MAX_RUNS_PER_CELL, strict=True,
                       description="runs a racing cell gets per round after the first")
    pairs: str = Field(default="reference",
                       description="compare every algorithm with the reference, or all pairs")
    margin: float = Field(default=0.0, ge=0, lt=0.5, allow_inf_nan=False,
                          description="equivalence margin on P(A's run beats B's) - 1/2")
    final_test: Literal["rank-sum", "sign", "none"] = Field(
        default="rank-sum", description="the closing look at max_runs for the comparisons still "
        "open there: the rank-sum test with Holm over them at half of alpha, the sign test at "
        "half of alpha, or none (docs/statistics.md, Racing); false and true, what jobs "
        "stored before the rank-sum look held, are none and sign")

    # The planned looks and the shares of alpha. Left out (null), they are those of the
    # default design (evidence.racing.default_design: with the rank-sum closing look a
    # Pocock-spent look every round, shares 0.05 / 0.8 / 0.15), written into the validated spec
    # so that a stored job keeps its design when a later default changes (store schema 6
    # wrote the race without looks into the specs stored before, schema 7 no futility and no
    # recycling).
    looks: list[int] | Literal["every-round"] | None = Field(
        default=None, max_length=MAX_RUNS_PER_CELL, description="planned looks: run counts "
        "(each min_runs + k * batch, below max_runs, increasing), or 'every-round' (each "
        "round's after the first), at which every comparison still open gets the rank-sum "
        "test at a group-sequential level (docs/statistics.md, Racing); [] races without "
        "looks. Default: 'every-round' with the rank-sum closing look, none with the others")
    look_share: float | None = Field(
        default=None, ge=0, lt=1, allow_inf_nan=False, description="the looks' share of alpha "
        "(> 0 with looks). Default: 0.8 with looks, 0 without")
    sequence_share: float | None = Field(
        default=None, gt=0, le=1, allow_inf_nan=False, description="the confidence "
        "sequence's share of alpha beside the rank-sum closing look (which gets the rest). "
        f"Default: 0.05 with looks, {SEQUENCE_SHARE} without")
    spending: Literal["obrien-fleming", "pocock"] | None = Field(
        default=None, description="how the looks' share is spent across them: Lan-DeMets "
        "O'Brien-Fleming or Pocock type. Default: pocock with looks")
    futility: float | None = Field(
        default=None, ge=0, lt=1, allow_inf_nan=False, description="stop a comparison at a "
        "look where its predictive power (the chance, by its own trend, that the closing "
        "rank-sum look calls it) is below this; 0 never. It costs power, never error "
        "(docs/statistics.md, Racing). Default: 0.05 with looks and the rank-sum closing "
        "look, else 0")
    recycle: bool | None = Field(
        default=None, strict=True, description="at a look, the looks' share of alpha of a "
        "comparison declared different goes to the open comparisons of its block (Holm's "
        "step-down within the block; docs/statistics.md, Racing); false: each keeps its own. "
        "Default: true with looks")

    @field_validator("looks", mode="before")
    @classmethod
    def _strict_looks(cls, v: Any) -> Any:
        # one error at racing.looks, not one per member of the union
        if v is None or v == EVERY_ROUND or (isinstance(v, list) and all(
                isinstance(n, int) and not isinstance(n, bool) for n in v)):
            return v
        raise ValueError(f"must be a list of integers (run counts) or {EVERY_ROUND!r}")

    @model_validator(mode="after")
    def _design_written(self) -> RacingSpec:
        """The design's fields left out filled in (the default design), so that the stored
        spec names them."""
        design = default_design(self.final_test, self.looks, self.look_share,
                                self.sequence_share, self.spending, self.futility,
                                self.recycle)
        design["looks"] = design["looks"] if isinstance(design["looks"], str) else list(
            design["looks"])
        for key, value in design.items():
            if getattr(self, key) is None:
                setattr(self, key, value)
        return self

    @field_validator("final_test", mode="before")
    @classmethod
    def _boolean_look(cls, v: Any) -> Any:
        # a spec written when the look was a boolean keeps its meaning: false none, true sign
        return ("sign" if v else "none") if isinstance(v, bool) else v

    @field_validator("pairs")
    @classmethod
    def _known_pairs(cls, v: str) -> str:
        if v not in PAIRS:
            raise ValueError(f"must be one of {', '.join(PAIRS)}, got {v!r}")
        return v

    def settings(self, runs: int) -> RaceSettings:
        design = default_design(self.final_test, self.looks, self.look_share,
                                self.sequence_share, self.spending, self.futility,
                                self.recycle)
        return RaceSettings(max_runs=runs, alpha=self.alpha, min_runs=self.min_runs,
                            batch=self.batch, pairs=self.pairs, margin=self.margin,
                            final_test=self.final_test, **design)


def check_racing(racing: RacingSpec, runs: int, algorithms: Sequence[str]) -> list[
        tuple[tuple[str, ...], str]]:
    """Problems of a racing field against its job, as (location under ``racing``, message)."""
    problems: list[tuple[tuple[str, ...], str]] = []
    if racing.max_runs is not None and racing.max_runs != runs:
        problems.append((("max_runs",), f"is the job's runs ({runs}); got {racing.max_runs}: "
                         "leave one of them out"))
    if racing.min_runs > runs:
        problems.append((("min_runs",), f"must be at most the job's runs ({runs}), got "
                         f"{racing.min_runs}"))
    if len(algorithms) < 2:
        problems.append(((), "a race needs at least two algorithms"))
    if not problems:
        try:  # the looks and shares against the job's runs (RaceSettings checks them)
            racing.settings(runs)
        except ValueError as e:
            field = str(e).split(" ", 1)[0].rstrip(":")
            problems.append(((field,) if field in RacingSpec.model_fields else (), str(e)))
    return problems


@dataclass(frozen=True)
class Blocks:
    """The job's cells grouped into blocks (one per function, dimension and whatever else the
    cell spec holds besides its algorithm): per block the cell indices in race order, the
    reference's cell last; ``of[cell]`` is a cell's block; ``comparisons`` counts the study's."""

    members: dict[str, list[tuple[int, str]]]
    of: dict[int, str]
    comparisons: int

    def names(self, block: str) -> list[str]:
        return [name for _, name in self.members[block]]


def block_key(cell_spec: dict[str, Any]) -> str:
    return json.dumps({k: v for k, v in cell_spec.items() if k not in _MEMBER_FIELDS},
                      sort_keys=True, separators=(",", ":"))


def group_blocks(cells: Iterable[tuple[int, dict[str, Any]]], reference: str | None,
                 pairs: str) -> Blocks:
    """Blocks of the cells ``(index, cell spec)``; ``reference`` (None: the last algorithm of each
    block in table order) is moved last in each block."""
    members: dict[str, list[tuple[int, str]]] = {}
    of: dict[int, str] = {}
    for idx, spec in cells:
        key = block_key(spec)
        members.setdefault(key, []).append((idx, str(spec["algorithm"])))
        of[idx] = key
    for cells_ in members.values():
        if reference is not None:
            cells_.sort(key=lambda c: c[1] == reference)  # stable: the reference goes last
    comparisons = sum(len(comparisons_per_block([n for _, n in c], pairs))
                      for c in members.values())
    return Blocks(members, of, comparisons)
