"""Which code a job runs, pinned at submission, and which workers have it.

A job is *pinned* when it is submitted: every optimizer, function (or suite) and planner it
names, with the origin and code digest the coordinator has for it (:func:`pin_names`). A cell
*requires* the keys of its extensions (:func:`requirements`: ``optimizer:GWO``,
``function:F14``, ``suite:bbob``, ``planner:ICOOT``; ``swarm:NAME`` requires the planner family
and optimizer NAME). A worker *advertises* the digests of everything it can run
(:func:`advertised`, sent with each lease request); it is leased a cell only when it has every
requirement with the pinned digest (:func:`runnable`), and a job that no live worker can run
says why (:func:`missing`).

Keys are ``<kind>:<name>``; advertised digests are the first :data:`ADVERTISED` hex digits of
the sha256 (a worker's word is all the coordinator has either way: this only tells honest
mismatches apart). Pure functions over the registries, no I/O beyond reading source files for
the digests.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from swarmpath.plugins.origin import SHORT, Origin

#: Hex digits of a digest a worker advertises (64 bits).
ADVERTISED = 16
#: The planner family ``swarm:<optimizer>`` as a requirement key.
SWARM_FAMILY = "planner:swarm:<optimizer>"


#: Most entries a worker may advertise, and the longest key (a hostile one is bounded).
MAX_ADVERTISED = 512
MAX_KEY_CHARS = 160
_DIGEST = re.compile(f"[0-9a-f]{{{ADVERTISED}}}")


def clean_extensions(value: Any) -> dict[str, str]:
    """A worker's advertisement from the bus, bounded: at most MAX_ADVERTISED string keys of at
    most MAX_KEY_CHARS, each to ADVERTISED lower-case hex digits. ValueError otherwise."""
    if not isinstance(value, dict):
        raise ValueError("extensions: must be an object of strings")
    if len(value) > MAX_ADVERTISED:
        raise ValueError(f"extensions: at most {MAX_ADVERTISED} entries, got {len(value)}")
    # sent with every lease request: a regular expression per digest (half the time of a set)
    digest = _DIGEST.fullmatch
    for k, v in value.items():
        if not isinstance(k, str) or not 0 < len(k) <= MAX_KEY_CHARS or ":" not in k:
            raise ValueError(f"extensions: key {str(k)[:40]!r} is not '<kind>:<name>' of at "
                             f"most {MAX_KEY_CHARS} characters")
        if not isinstance(v, str) or digest(v) is None:
            raise ValueError(f"extensions[{k[:40]!r}]: must be {ADVERTISED} hex digits")
    return dict(value)


def key(kind: str, name: str) -> str:
    return f"{kind}:{name}"


def split_key(text: str) -> tuple[str, str]:
    kind, _, name = text.partition(":")
    return kind, name


def function_key(name: str) -> str:
    """A function's requirement: its suite's for a suite function (instances included)."""
    from swarmpath.functions.registry import suite_of

    suite = suite_of(name)
    return key("suite", suite) if suite is not None else key("function", name)


def planner_keys(name: str) -> list[str]:
    """A planner's requirements: itself, or the family and the optimizer for swarm:NAME."""
    if name.startswith("swarm:"):
        return [SWARM_FAMILY, key("optimizer", name[len("swarm:"):])]
    return [key("planner", name)]


def requirements(cell: Any) -> list[str]:
    """The keys a cell (BenchmarkCell or MapCell, or their dict) requires."""
    kind = cell.get("kind") if isinstance(cell, Mapping) else getattr(cell, "kind", None)
    get = cell.get if isinstance(cell, Mapping) else (lambda k: getattr(cell, k))
    if kind == "benchmark":
        return [key("optimizer", str(get("algorithm"))), function_key(str(get("function")))]
    return planner_keys(str(get("planner")))


def origin_of(requirement: str) -> Origin:
    """The origin this process's registry has for a requirement key (KeyError/ValueError when
    it does not know it)."""
    kind, name = split_key(requirement)
    if kind == "optimizer":
        from swarmpath.optimizers.registry import REGISTRY as optimizers

        return optimizers.origin(name)
    if kind == "function":
        from swarmpath.functions.registry import REGISTRY as functions

        return functions.origin(name)
    if kind == "suite":
        from swarmpath.functions.registry import SUITES

        return SUITES.origin(name)
    if kind == "planner":
        from swarmpath.planners.base import REGISTRY as planners

        return planners.origin("swarm:PSO" if requirement == SWARM_FAMILY else name)
    raise KeyError(f"unknown kind of extension {kind!r}")


def pin_names(keys: Iterable[str]) -> dict[str, dict[str, str]]:
    """Each key with the origin and digest this process has for it (a name it does not know is
    left out: a job is validated against the registries before it is pinned)."""
    out = {}
    for k in dict.fromkeys(keys):
        try:
            origin = origin_of(k)
        except (KeyError, ValueError):
            continue
        out[k] = {"source": origin.source, "origin": origin.describe(),
                  "version": origin.version, "digest": origin.digest}
    return out


def spec_requirements(spec: Any) -> list[str]:
    """Every requirement of a job spec (BenchmarkJobSpec or MapJobSpec), in spec order."""
    if spec.kind == "benchmark":
        keys = [key("optimizer", a) for a in spec.algorithms]
        keys += [function_key(f) for f in spec.functions]
    else:
        keys = [k for p in spec.planners for k in planner_keys(p)]
    return list(dict.fromkeys(keys))


def study_pins(algorithms: Iterable[str] = (), functions: Iterable[str] = (),
               planners: Iterable[str] = ()) -> dict[str, dict[str, str]]:
    """What a local study ran (its --json document's ``extensions``): every optimizer, function
    (or suite) and planner with origin, version and digest, as a job is pinned."""
    keys = [key("optimizer", a) for a in algorithms] + [function_key(f) for f in functions]
    keys += [k for p in planners for k in planner_keys(p)]
    return pin_names(keys)


def advertised() -> dict[str, str]:
    """What this process can run: every optimizer, stand-alone function, suite and planner
    (and the swarm family), each with the first ADVERTISED digits of its digest."""
    from swarmpath.plugins.catalog import extensions

    out = {}
    for row in extensions():
        out[key(row.kind, row.name)] = row.digest[:ADVERTISED]
    return out


def runnable(needs: Sequence[str], pins: Mapping[str, Mapping[str, str]],
             ads: Mapping[str, str]) -> bool:
    """Whether a worker advertising ``ads`` has every requirement with its pinned digest (a
    requirement the job did not pin, e.g. a job from before pins, only needs the name)."""
    for k in needs:
        have = ads.get(k)
        if have is None:
            return False
        pinned = pins.get(k, {}).get("digest")
        if pinned and not pinned.startswith(have):
            return False
    return True


def missing(needs: Sequence[str], pins: Mapping[str, Mapping[str, str]],
            workers: Mapping[str, Mapping[str, str]]) -> list[str]:
    """Why no worker of ``workers`` (id -> advertised) runs a cell needing ``needs``: one phrase
    per requirement no worker has as pinned (``no live worker has optimizer MyGWO (digest
    3f2a9c1b4d5e)``, ``... ; worker w1 has digest 77aa...``)."""
    out = []
    for k in needs:
        pinned = pins.get(k, {}).get("digest", "")
        holders = {w: ads[k] for w, ads in workers.items() if k in ads}
        if any(not pinned or pinned.startswith(d) for d in holders.values()):
            continue
        kind, name = split_key(k)
        text = f"no live worker has {kind} {name}"
        if pinned:
            text += f" (digest {pinned[:SHORT]})"
        if holders:
            w, d = sorted(holders.items())[0]
            others = f" and {len(holders) - 1} more" if len(holders) > 1 else ""
            text += f"; worker {w}{others} has digest {d[:SHORT]}"
        out.append(text)
    return out
