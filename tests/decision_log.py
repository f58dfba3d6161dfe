"""Test helper: run an episode while recording every decision its planner made."""

import numpy as np

from swarmpath.planners import Episode


def run_recording(episode: Episode) -> tuple[object, list[tuple[np.ndarray, object]]]:
    """Run ``episode`` to its end; returns its outcome and (robot position, decision) pairs."""
    made = []
    decide = episode.planner.decide

    def record(obs):
        d = decide(obs)
        made.append((np.array([obs.pose.x, obs.pose.y]), d))
        return d

    episode.planner.decide = record  # type: ignore[method-assign]
    return episode.run(), made
