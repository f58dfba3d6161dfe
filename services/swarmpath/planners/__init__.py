"""Path planners (swarm local planners, RFO-GWO global planners, OMPL baselines) and the episode.

>>> from swarmpath.planners import Episode, list_planners
>>> from swarmpath.world import get_map
"""

from swarmpath.planners.base import (
    Decision,
    Observation,
    Planner,
    PlannerError,
    get_planner,
    list_planners,
    register_planner,
)
from swarmpath.planners.episode import Episode, RunOutcome, scenario_optimum

__all__ = [
    "Decision",
    "Episode",
    "Observation",
    "Planner",
    "PlannerError",
    "RunOutcome",
    "get_planner",
    "list_planners",
    "register_planner",
    "scenario_optimum",
]
