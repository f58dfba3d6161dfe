"""What a job runs, in one line for job lists (``GET /jobs``, the dashboard's jobs page,
``swarmpath status``): ``GWO, PSO x F1-F13 x D 10, 30`` or ``MFB, ICOOT x mfb-static, tb3``.
Plain functions over the stored (normalized) spec."""

from __future__ import annotations

import re
from typing import Any

MAX_CHARS = 200


def _ranges(names: list[str]) -> list[str]:
    """``F1, F2, F3, F5`` -> ``F1-F3, F5`` (runs of one prefix and consecutive numbers)."""
    out: list[str] = []
    run: list[tuple[str, int]] = []

    def close() -> None:
        if run:
            first, last = run[0], run[-1]
            out.append(f"{first[0]}{first[1]}" if len(run) == 1 else
                       f"{first[0]}{first[1]}-{last[0]}{last[1]}")
            run.clear()

    for name in names:
        m = re.fullmatch(r"(.*?)(\d+)", name)
        if m is None:
            close()
            out.append(name)
            continue
        key = (m.group(1), int(m.group(2)))
        if run and (run[-1][0] != key[0] or run[-1][1] + 1 != key[1]):
            close()
        run.append(key)
    close()
    return out


def _listed(items: list[str]) -> str:
    return ", ".join(items)


def contents(spec: dict[str, Any]) -> str:
    """The line for a stored job spec (benchmark or map); at most MAX_CHARS characters."""
    if spec.get("kind") == "map":
        maps = [m if isinstance(m, str) else str(m.get("name", "?")) for m in spec.get("maps", [])]
        text = f"{_listed(list(spec.get('planners', [])))} x {_listed(maps)}"
    else:
        dims = ", ".join(str(d) for d in spec.get("dims", []))
        text = (f"{_listed(list(spec.get('algorithms', [])))} x "
                f"{_listed(_ranges(list(spec.get('functions', []))))} x D {dims}")
    return text if len(text) <= MAX_CHARS else text[:MAX_CHARS - 3] + "..."
