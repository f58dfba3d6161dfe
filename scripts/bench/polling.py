"""Waiting on a service the benchmark started (farm.py, service.py): poll a condition until it
holds, failing at once when the service's process has exited and after a timeout otherwise."""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable
from typing import Any

import httpx


def wait_until(cond: Callable[[], Any], timeout: float, what: str,
               exited: Callable[[], str | None], where: str, poll: float = 0.2) -> None:
    """Poll ``cond()`` (an HTTP error or a missing key counts as not yet) every ``poll`` s.
    ``exited()`` says why the service is gone (None while it runs): a RuntimeError "<why>
    waiting for <what>; <where>"; a TimeoutError after ``timeout`` s. ``where`` points at the
    service's log."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        gone = exited()
        if gone is not None:
            raise RuntimeError(f"{gone} waiting for {what}; {where}")
        with contextlib.suppress(httpx.HTTPError, ValueError, KeyError):
            if cond():
                return
        time.sleep(poll)
    raise TimeoutError(f"timed out waiting for {what}; {where}")
