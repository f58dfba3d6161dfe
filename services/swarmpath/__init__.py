"""swarmpath: swarm-intelligence optimizers and robot path planners, run as reproducible studies."""

__version__ = "0.1.0"

__all__ = ["__version__", "load_results"]


def load_results(source: str, url: str | None = None) -> object:
    """A job's runs as a pandas DataFrame, from an export file or a job id on the coordinator at
    ``url``: :func:`swarmpath.evidence.exports.load_results` (needs the ``data`` extra)."""
    from swarmpath.evidence.exports import load_results as load

    return load(source, url)
