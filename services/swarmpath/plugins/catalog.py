"""Every extension, built-in or plugin, with its origin and code digest: what ``swarmpath plugins``
prints and the coordinator's ``/catalog`` carries.

One row per optimizer, stand-alone function, suite and planner (the ``swarm:<optimizer>`` family
is one row: it exists for every optimizer), in registry order, built-ins first. Entry points
that failed to load are listed apart (:func:`problems`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

from swarmpath.plugins.loading import load_all
from swarmpath.plugins.loading import problems as load_problems
from swarmpath.plugins.origin import SHORT, Origin

KINDS = ("optimizer", "function", "suite", "planner")


@dataclass(frozen=True)
class Extension:
    kind: str
    name: str
    source: str  # built-in, distribution, file, module
    label: str  # swarmpath, the distribution's name, the file's path, the module's name
    version: str
    digest: str  # sha256 of its code (hex)
    summary: str = ""
    reference: str = ""
    defaults: dict[str, Any] = field(default_factory=dict)
    choices: dict[str, list[str]] = field(default_factory=dict)

    @property
    def origin(self) -> str:
        """``built-in``, ``distribution NAME VERSION``, ``file PATH``."""
        return Origin(self.source, self.label, self.version).describe()

    @property
    def short_digest(self) -> str:
        return self.digest[:SHORT]

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "origin": self.origin}


def origin_fields(origin: Origin) -> dict[str, str]:
    """The origin of a name as the catalog and the job pins carry it."""
    return {"source": origin.source, "origin": origin.describe(), "version": origin.version,
            "digest": origin.digest}


def _row(kind: str, name: str, origin: Origin, **extra: Any) -> Extension:
    return Extension(kind, name, origin.source, origin.label, origin.version, origin.digest,
                     **extra)


def extensions(kinds: tuple[str, ...] = KINDS, builtin: bool | None = None) -> list[Extension]:
    """The rows of the given kinds (``builtin``: only built-ins, or only plugins)."""
    load_all()
    rows: list[Extension] = []
    if "optimizer" in kinds:
        from swarmpath.optimizers.registry import REGISTRY as optimizers

        for name in optimizers.names(builtin):
            cls = optimizers.get(name)
            rows.append(_row("optimizer", name, optimizers.origin(name), summary=cls.summary,
                             reference=cls.reference, defaults=dict(cls.defaults),
                             choices={k: list(v) for k, v in cls.choices.items()}))
    if "function" in kinds or "suite" in kinds:
        from swarmpath.functions.registry import REGISTRY as functions
        from swarmpath.functions.registry import SUITES

        if "function" in kinds:
            for name in functions.names(builtin):
                fn = functions.get(name)
                rows.append(_row("function", name, functions.origin(name),
                                 summary=fn.description, reference=fn.reference))
        if "suite" in kinds:
            for name in SUITES.names(builtin):
                suite = SUITES.get(name)
                rows.append(_row("suite", name, SUITES.origin(name),
                                 summary=f"{len(suite.members)} functions: {suite.description}",
                                 reference=suite.reference))
    if "planner" in kinds:
        rows.extend(_planners(builtin))
    return rows


def _planners(builtin: bool | None) -> list[Extension]:
    from swarmpath.planners.base import REGISTRY as planners

    rows = []
    for name in planners.names(builtin):
        cls = planners.get(name)
        rows.append(_row("planner", name, planners.origin(name), summary=cls.description,
                         reference=cls.reference, defaults=dict(cls.defaults),
                         choices={k: list(v) for k, v in cls.choices.items()}))
    if builtin is not False:  # the families (swarm:<optimizer>), built-in code
        for family in planners.families():
            prefix = family.removesuffix("<name>")
            example = planners.get(prefix + "PSO")
            rows.append(_row(
                "planner", family.replace("<name>", "<optimizer>"), planners.origin(prefix + "PSO"),
                summary="the seeds' swarm local planner driven by any registered optimizer "
                "(its parameters: the planner's, and the optimizer's as optimizer.<name>)",
                reference=example.reference.split(";")[0],
                defaults={k: v for k, v in example.defaults.items()
                          if k != "optimizer" and not k.startswith("optimizer.")},
                choices={k: list(v) for k, v in example.choices.items()
                         if not k.startswith("optimizer.")}))
    return rows


def problems() -> list[dict[str, str]]:
    """Entry points left out because they failed to load (group, name, origin, message)."""
    load_all()
    return [asdict(p) for p in load_problems()]
