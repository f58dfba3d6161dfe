"""Messages for unknown names: the near miss first ("did you mean 'GWO'?"), then what is valid.
Pure (difflib); used by the registries, the CLI and the job-spec validation alike."""

from __future__ import annotations

import difflib
from collections.abc import Iterable


def closest(name: str, valid: Iterable[str]) -> str | None:
    """The valid name nearest to ``name`` (case-insensitive, difflib ratio >= 0.6), if any."""
    names = list(valid)
    by_lower = {v.lower(): v for v in names}
    if name.lower() in by_lower:
        return by_lower[name.lower()]
    match = difflib.get_close_matches(name.lower(), list(by_lower), n=1, cutoff=0.6)
    return by_lower[match[0]] if match else None


def did_you_mean(name: str, valid: Iterable[str]) -> str:
    """``" (did you mean 'GWO'?)"`` or ``""``."""
    near = closest(name, valid)
    return f" (did you mean {near!r}?)" if near is not None and near != name else ""


def unknown(kind: str, name: str, valid: Iterable[str]) -> str:
    """``unknown algorithm 'GW0' (did you mean 'GWO'?); valid: PSO, ..., GWO``."""
    names = list(valid)
    return f"unknown {kind} {name!r}{did_you_mean(name, names)}; valid: {', '.join(names)}"
