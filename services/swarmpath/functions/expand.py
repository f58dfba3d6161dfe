"""The function names users type: names, suite names, ranges, comma-separated.

* a registered name: ``F5``, ``F6-floor``, a plugin's ``pressure-vessel``, a suite function
  ``bbob:f3`` or one of its instances ``bbob:f3@i7``;
* a suite's name (case-insensitive): its members, in its order (``bbob``, ``cec2017``);
* a range of stand-alone functions ``LO-HI``: LO is a registered name ending in a number and HI
  repeats its prefix (or a tail of it) with another number, e.g. ``F1-F13``, ``F12-14``: every
  registered name made of that prefix and a number in [LO, HI], in numeric order. Both ends
  must be registered; numbers no function has are skipped. Ranges cover plugins' functions: a
  plugin registering F14-F23 makes ``F1-F23`` valid;
* a range within a suite: ``bbob:f1-f5``, ``cec2017:F3-F10`` (the suite's members between the
  two, in the suite's order).
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from swarmpath.functions.registry import REGISTRY, SUITES, get_function

_NUMBERED = re.compile(r"^(.*?)(\d+)$")


def expand_function_names(spec: str | Iterable[str]) -> list[str]:
    """'F1-F13', 'F1,F5,F9', 'bbob', 'bbob:f1-f5' or mixtures (or a list of such parts) ->
    registered function names, in the order given. KeyError naming the valid names when a part
    is none of those."""
    parts = spec.split(",") if isinstance(spec, str) else list(spec)
    names: list[str] = []
    for part in (p.strip() for p in parts):
        if not part:
            continue
        if part in REGISTRY:
            names.append(part)
            continue
        ranged = _range(part)
        if ranged is not None:
            names.extend(ranged)
            continue
        suites = {n.lower(): n for n in SUITES.names()}
        if part.lower() in suites:
            names.extend(SUITES.get(suites[part.lower()]).members)
            continue
        expanded = _suite_range(part)
        if expanded is not None:
            names.extend(expanded)
            continue
        get_function(part)  # a suite function or instance; else KeyError listing valid names
        names.append(part)
    return names


def _range(part: str) -> list[str] | None:
    """The stand-alone functions of range ``part``, or None when it is no such range."""
    registered = REGISTRY.names()
    for i, ch in enumerate(part):
        if ch != "-":
            continue
        lo, hi = part[:i], part[i + 1:]
        low, high = _NUMBERED.match(lo), _NUMBERED.match(hi)
        if lo not in registered or low is None or high is None:
            continue
        prefix, tail = low.group(1), high.group(1)
        if not prefix.lower().endswith(tail.lower()):
            continue
        a, b = int(low.group(2)), int(high.group(2))
        numbered = []
        for name in registered:
            m = _NUMBERED.match(name)
            if m is not None and m.group(1) == prefix and a <= int(m.group(2)) <= b:
                numbered.append((int(m.group(2)), name))
        if a > b:
            raise KeyError(f"function range {part!r} runs backwards")
        if b not in {n for n, _ in numbered}:
            raise KeyError(f"function range {part!r}: {prefix}{b} is not registered; "
                           f"registered: {', '.join(registered)}")
        return [name for _, name in sorted(numbered)]
    return None


def _suite_range(part: str) -> list[str] | None:
    """'bbob:f1-f5', 'cec2017:F3-F10' -> the suite's members numbered in the range (inclusive);
    None if ``part`` is not such a range."""
    suite_name, colon, span = part.partition(":")
    lo, dash, hi = span.partition("-")
    if not (colon and dash) or suite_name not in SUITES.names():
        return None
    suite = SUITES.get(suite_name)
    names = [f.name for f in suite.functions]
    first, last = f"{suite_name}:{lo}", f"{suite_name}:{hi}"
    if first not in names or last not in names:
        return None
    a, b = names.index(first), names.index(last)
    if a > b:
        raise KeyError(f"function range {part!r} runs backwards")
    return [n for n in names[a:b + 1] if n in suite.members]
