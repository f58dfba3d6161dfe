"""swarmpath: swarm-intelligence optimizers and robot path planners, run as reproducible studies."""

__version__ = "0.1.0"
