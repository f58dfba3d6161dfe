"""Small helpers shared by the coordinator's layers: one-line error texts and JSON-safe values."""

from __future__ import annotations

import math
from typing import Any


def short(exc: BaseException, limit: int = 300) -> str:
    """One line: a validation error as 'field: message; ...', anything else as its text."""
    errors = getattr(exc, "errors", None)
    if callable(errors):
        try:
            items = errors(include_url=False, include_input=False)
        except TypeError:  # pragma: no cover - not a pydantic error after all
            items = None
        if items:
            parts = [f"{'.'.join(str(p) for p in e['loc']) or '(message)'}: {e['msg']}"
                     for e in items[:3]]
            more = f" (+{len(items) - 3} more)" if len(items) > 3 else ""
            text = "; ".join(parts) + more
            return text if len(text) <= limit else text[: limit - 3] + "..."
    text = " ".join(str(exc).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def json_safe(value: Any) -> Any:
    """Non-finite floats -> 'inf'/'-inf'/'nan' (the store's REST convention), recursively."""
    if isinstance(value, float):
        if math.isfinite(value):
            return value
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    return value
