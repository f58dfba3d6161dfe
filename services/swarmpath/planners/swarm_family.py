"""The planner family ``swarm:<optimizer>``: the seeds' swarm local planner driven by any
registered optimizer, built-in or plugin (a plugin optimizer gets a planner without writing one).

The named presets (ICOOT, GWO, ...) fix their optimizer; ``swarm:NAME`` is how a table, a job
spec, the REST API and an MCAP file name the planner driven by NAME.
"""

from __future__ import annotations

from swarmpath.optimizers import get_optimizer
from swarmpath.planners.base import REGISTRY, PlannerError
from swarmpath.planners.swarm_local import (
    MFB_PAPER,
    OPTIMIZER_PREFIX,
    SWARM,
    SwarmLocalPlanner,
)

_FAMILY: dict[str, type[SwarmLocalPlanner]] = {}


def swarm_planner(name: str) -> type[SwarmLocalPlanner]:
    """The planner ``swarm:<optimizer>``: the seeds' swarm local planner (the settings of its GWO
    and PSO presets: 20 agents, 20 iterations, the MFB paper's 12 sensors) driven by any
    registered optimizer, built-in or plugin. Its parameters are the planner's and the
    optimizer's own as ``optimizer.<parameter>``; tables, REST and MCAP name it ``swarm:NAME``."""
    wanted = name[len(SWARM):]
    try:
        opt_cls = get_optimizer(wanted)
    except KeyError as exc:
        raise PlannerError(f"planner {name!r}: {exc.args[0]}") from None
    cached = _FAMILY.get(opt_cls.name)
    if cached is not None and cached.optimizer_class is opt_cls:
        return cached
    attrs = {
        "__module__": __name__,
        "name": f"{SWARM}{opt_cls.name}",
        "description": f"{opt_cls.name} driving the seeds' swarm local planner",
        "reference": f"{MFB_PAPER}; optimizer: {opt_cls.reference or opt_cls.name}",
        "default_sensors": "mfb-12",
        "defaults": {**SwarmLocalPlanner.defaults, "optimizer": opt_cls.name,
                     **{OPTIMIZER_PREFIX + k: v for k, v in opt_cls.defaults.items()}},
        "choices": {**SwarmLocalPlanner.choices,
                    **{OPTIMIZER_PREFIX + k: v for k, v in opt_cls.choices.items()}},
        "optimizer_class": opt_cls,
    }
    cls = type("Swarm_" + "".join(c if c.isalnum() else "_" for c in opt_cls.name),
               (SwarmLocalPlanner,), attrs)
    _FAMILY[opt_cls.name] = cls
    return cls


REGISTRY.add_family(SWARM, swarm_planner)
