"""A race's settings: its parameters, planned looks and shares of alpha, and the default design
of a new race. The rule they parametrize: :mod:`swarmpath.evidence.racing` and
docs/statistics.md, "Racing"."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

from swarmpath.evidence.group_sequential import SPENDING, nominal_levels

PAIRS = ("reference", "all")
#: The closing looks at max_runs (module text); the first is the default of new races.
CLOSING = ("rank-sum", "sign", "none")
#: The confidence sequence's share of alpha when the rank-sum look closes the race without
#: planned looks (the race of jobs stored before the looks were the default).
SEQUENCE_SHARE = 0.5
#: ``looks`` meaning a look at every round after the first: ``min_runs + k * batch`` for
#: k >= 1, below ``max_runs`` (module text), whatever the job's runs.
EVERY_ROUND = "every-round"
#: The design of a new race with the rank-sum closing look (docs/statistics.md, "Planned
#: looks"): a Pocock-spent look every round, the shares of alpha sequence 0.05 / looks 0.8 /
#: closing look 0.15 (the best of the designs replayed over Table 2, docs/benchmarks.md), and a
#: comparison stopped at a look where its predictive power is below 0.05 (``futility``), and
#: the looks' share of a comparison declared different passed on within its block
#: (``recycle``, Holm's step-down).
DEFAULT_DESIGN: dict[str, Any] = {"looks": EVERY_ROUND, "look_share": 0.8,
                                  "sequence_share": 0.05, "spending": "pocock",
                                  "futility": 0.05, "recycle": True}

__all__ = ["CLOSING", "DEFAULT_DESIGN", "EVERY_ROUND", "PAIRS", "SEQUENCE_SHARE", "RaceSettings",
           "default_design"]


def default_design(final_test: str, looks: Sequence[int] | str | None = None,
                   look_share: float | None = None, sequence_share: float | None = None,
                   spending: str | None = None, futility: float | None = None,
                   recycle: bool | None = None) -> dict[str, Any]:
    """The planned looks, shares, futility threshold and recycling of a new race, those given
    kept (None: not given). With the rank-sum closing look and no ``looks`` given:
    :data:`DEFAULT_DESIGN`; with the sign look or none: no looks, no futility (those races are
    as they were). Looks given without shares get the default design's, its recycling, and with
    the rank-sum closing look its futility; ``looks=[]`` is the race without looks (sequence
    share 0.5, no futility, nothing to recycle), as stored before the looks were the default."""
    if looks is None:
        looks = EVERY_ROUND if final_test == CLOSING[0] else ()
    looked = looks == EVERY_ROUND or bool(looks)
    if look_share is None:
        look_share = DEFAULT_DESIGN["look_share"] if looked else 0.0
    if sequence_share is None:
        sequence_share = (DEFAULT_DESIGN["sequence_share"] if looked and final_test == CLOSING[0]
                          else SEQUENCE_SHARE)
    if spending is None:  # without looks it spends nothing: what such races always stored
        spending = DEFAULT_DESIGN["spending"] if looked else SPENDING[0]
    if futility is None:  # futility is judged at a look against the closing look's level
        futility = DEFAULT_DESIGN["futility"] if looked and final_test == CLOSING[0] else 0.0
    if recycle is None:
        recycle = DEFAULT_DESIGN["recycle"] if looked else False
    return {"looks": looks if isinstance(looks, str) else tuple(looks),
            "look_share": look_share, "sequence_share": sequence_share, "spending": spending,
            "futility": futility, "recycle": recycle}


@dataclass(frozen=True)
class RaceSettings:
    """A race's parameters. ``margin`` is on the scale of theta (the probability that one
    algorithm's run beats the other's): 0 means differences only, no equivalence decisions."""

    max_runs: int
    alpha: float = 0.05
    min_runs: int = 10
    batch: int = 10
    pairs: str = "reference"
    margin: float = 0.0
    #: the closing look at max_runs for the comparisons still open there (module text)
    final_test: str = CLOSING[0]
    #: planned looks: run counts at which open comparisons get the rank-sum test, or
    #: :data:`EVERY_ROUND` (module text)
    looks: tuple[int, ...] | str = ()
    #: the looks' share of alpha (0 without looks)
    look_share: float = 0.0
    #: the confidence sequence's share of alpha under the rank-sum closing look
    sequence_share: float = SEQUENCE_SHARE
    #: how the looks' share is spent across them (:data:`SPENDING`)
    spending: str = SPENDING[0]
    #: stop a comparison at a look where its predictive power (the chance, by its own trend,
    #: that the closing look would call it: group_sequential.predictive_power) is below this;
    #: 0 never (module text of swarmpath.evidence.racing)
    futility: float = 0.0
    #: at a look, the looks' share of the comparisons of a block declared different goes to
    #: the block's others (Holm's step-down within the block; module text of
    #: swarmpath.evidence.racing); False: each keeps its own share (Bonferroni)
    recycle: bool = False

    def __post_init__(self) -> None:
        if self.looks != EVERY_ROUND:
            if isinstance(self.looks, str):
                raise ValueError(f"looks must be run counts or {EVERY_ROUND!r}, got "
                                 f"{self.looks!r}")
            object.__setattr__(self, "looks", tuple(int(n) for n in self.looks))
        if not 0.0 < self.alpha < 1.0:
            raise ValueError(f"alpha must be in (0, 1), got {self.alpha}")
        if self.min_runs < 1:
            raise ValueError(f"min_runs must be >= 1, got {self.min_runs}")
        if self.max_runs < self.min_runs:
            raise ValueError(f"max_runs ({self.max_runs}) must be >= min_runs ({self.min_runs})")
        if self.batch < 1:
            raise ValueError(f"batch must be >= 1, got {self.batch}")
        if self.pairs not in PAIRS:
            raise ValueError(f"pairs must be one of {', '.join(PAIRS)}, got {self.pairs!r}")
        if not 0.0 <= self.margin < 0.5:
            raise ValueError(f"margin must be in [0, 0.5), got {self.margin}")
        if self.final_test not in CLOSING:
            raise ValueError(f"final_test must be one of {', '.join(CLOSING)}, got "
                             f"{self.final_test!r}")
        self._check_looks()

    def _check_looks(self) -> None:
        """The planned looks and the shares of alpha (module text)."""
        if self.spending not in SPENDING:
            raise ValueError(f"spending must be one of {', '.join(SPENDING)}, got "
                             f"{self.spending!r}")
        if not 0.0 < self.sequence_share <= 1.0:
            raise ValueError(f"sequence_share must be in (0, 1], got {self.sequence_share}")
        if self.final_test != "rank-sum" and self.sequence_share != SEQUENCE_SHARE:
            raise ValueError("sequence_share is the sequence's share beside the rank-sum "
                             f"closing look; final_test {self.final_test!r} sets it itself")
        if not 0.0 <= self.look_share < 1.0:
            raise ValueError(f"look_share must be in [0, 1), got {self.look_share}")
        if bool(self.looks) != (self.look_share > 0.0):  # every round: a truthy string
            raise ValueError("looks need a look_share > 0 and a look_share needs looks")
        if self.looks and self.final_test == "sign":
            raise ValueError("looks go with final_test rank-sum or none, not sign")
        if not 0.0 <= self.futility < 1.0:
            raise ValueError(f"futility must be in [0, 1), got {self.futility}")
        if self.recycle and not self.looks:
            raise ValueError("recycle passes on the planned looks' share: it needs looks")
        if self.futility and not (self.looks and self.final_test == "rank-sum"):
            raise ValueError("futility is judged at planned looks against the rank-sum "
                             "closing look: it needs looks and final_test rank-sum")
        if self.final_test == "rank-sum" and self.sequence_share + self.look_share >= 1.0:
            raise ValueError(f"sequence_share ({self.sequence_share}) + look_share "
                             f"({self.look_share}) must leave the closing look a share (< 1)")
        for i, n in enumerate(self.look_runs):
            if not (self.min_runs <= n < self.max_runs and (n - self.min_runs) % self.batch == 0):
                raise ValueError(f"looks: {n} is not a round's run count below max_runs "
                                 f"(min_runs {self.min_runs} + k * batch {self.batch} < "
                                 f"{self.max_runs})")
            if i and n <= self.look_runs[i - 1]:
                raise ValueError(f"looks must increase, got {list(self.look_runs)}")

    @property
    def look_runs(self) -> tuple[int, ...]:
        """The planned looks' run counts: ``looks``, or every round's after the first below
        ``max_runs`` (:data:`EVERY_ROUND`; none when the race has at most two rounds). The
        first round is left out: its ``min_runs`` runs a cell are where the rank-sum's normal
        approximation, which the looks' boundaries assume, is least accurate, and it is the
        schedule replayed over Table 2 (docs/benchmarks.md)."""
        if self.looks == EVERY_ROUND:
            return tuple(range(self.min_runs + self.batch, self.max_runs, self.batch))
        return self.looks  # type: ignore[return-value]

    @property
    def _look_share(self) -> float:
        """The looks' share of alpha as spent: 0 when every round leaves no look (a race of
        one or two rounds), its share then going to the closing look (or the sequence)."""
        return self.look_share if self.look_runs else 0.0

    def levels(self, comparisons: int) -> tuple[float, float]:
        """Each comparison's level for the confidence sequence and for the closing sign test
        (0: none): Bonferroni over the study's ``comparisons``, shared with the closing look
        (module text)."""
        level = self.alpha / max(comparisons, 1)
        if self.final_test == "sign":
            return level / 2, level / 2
        if self.final_test == "rank-sum":
            return level * self.sequence_share, 0.0
        return level * (1.0 - self._look_share), 0.0

    @property
    def closing_alpha(self) -> float:
        """The level of the rank-sum look's Holm procedure over the study (0: no such look)."""
        if self.final_test != "rank-sum":
            return 0.0
        return self.alpha * (1.0 - self.sequence_share - self._look_share)

    def look_levels(self, comparisons: int, weight: float = 1.0) -> dict[int, float]:
        """Each planned look's nominal level (the two-sided p to be below) for one comparison:
        ``alpha * look_share * weight / comparisons`` spent across the looks (module text);
        ``weight`` > 1 is a comparison holding shares passed on to it (``recycle``)."""
        runs = self.look_runs
        if not runs:
            return {}
        share = self.alpha * self.look_share * weight / max(comparisons, 1)
        return dict(zip(runs, nominal_levels(runs, share, self.spending), strict=True))

    def allowance(self, round_: int) -> int:
        """Runs a racing cell may have in round ``round_`` (0-based)."""
        return min(self.min_runs + round_ * self.batch, self.max_runs)

    @property
    def rounds(self) -> int:
        """The number of rounds of a cell that never stops early."""
        return 1 + -(-(self.max_runs - self.min_runs) // self.batch)

    def to_json(self) -> dict[str, Any]:
        looks = self.looks if isinstance(self.looks, str) else list(self.looks)
        return {**asdict(self), "looks": looks}
