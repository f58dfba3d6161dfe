"""What this worker can run (advertised with every lease request) and whether a granted lease
is among it: the worker's side of pinned extensions (swarmpath.plugins.pins).

A lease carries the digests its job was pinned to. A worker whose code for one of them differs
(or that cannot load it) does not run the lease: it holds nothing for it (the coordinator
requeues the runs when the lease expires, for a worker that has the code) and stops advertising
that extension. Its runs are never reported as failed for want of code.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping

from swarmpath.plugins.origin import SHORT
from swarmpath.plugins.pins import advertised, origin_of, split_key

log = logging.getLogger("swarmpath.worker")

#: The first words of the failure text of a lease its slot could not run for want of code.
UNAVAILABLE = "ExtensionUnavailable"


class ExtensionUnavailable(Exception):
    """A lease names an extension this process does not have as pinned."""


def unavailable(outcome: object) -> bool:
    """Whether a lease's outcome is an ExtensionUnavailable (itself, or its text from a slot
    process: ``[module.]ExtensionUnavailable: ...``)."""
    if isinstance(outcome, ExtensionUnavailable):
        return True
    return isinstance(outcome, BaseException) and str(outcome).split(":", 1)[0].endswith(
        UNAVAILABLE)


def unmet(pins: Mapping[str, str]) -> list[str]:
    """The pinned extensions this process lacks or has other code for, as phrases."""
    out = []
    for key, digest in pins.items():
        kind, name = split_key(key)
        try:
            have = origin_of(key).digest
        except Exception:  # not registered here, or its plugin does not load
            out.append(f"{kind} {name} is not installed here")
            continue
        same = have == digest if len(digest) >= len(have) else have.startswith(digest)
        if not same:
            out.append(f"{kind} {name} here has digest {have[:SHORT]}, the job pinned "
                       f"{digest[:SHORT]}")
    return out


def check_pins(pins: Mapping[str, str], cell: str) -> None:
    """ExtensionUnavailable naming what is missing, unless every pin is met here."""
    missing = unmet(pins)
    if missing:
        raise ExtensionUnavailable(f"{cell}: {'; '.join(missing)}")


class Capabilities:
    """What the worker advertises: everything it can run, less what turned out unusable."""

    def __init__(self) -> None:
        self._all = advertised()
        self.unusable: set[str] = set()

    def advertisement(self) -> dict[str, str]:
        return {k: v for k, v in self._all.items() if k not in self.unusable}

    def refuse(self, pins: Mapping[str, str], why: str) -> None:
        """A lease could not run here: stop advertising its unmet extensions."""
        bad = {k for k in pins if unmet({k: pins[k]})} or set(pins)
        if not bad <= self.unusable:
            log.warning("not advertising %s any more: %s", ", ".join(sorted(bad)), why)
        self.unusable |= bad
