"""The coordinator's clock: ``Coordinator.tick()`` once a second in a daemon thread."""

from __future__ import annotations

import logging
import threading

from swarmpath.service.coordinator import Coordinator

log = logging.getLogger("swarmpath.coordinator")


class Ticker:
    """Calls ``core.tick()`` every ``seconds`` in a daemon thread; errors are logged."""

    def __init__(self, core: Coordinator, seconds: float = 1.0):
        self.core = core
        self.seconds = seconds
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="coordinator-tick", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.seconds):
            try:
                self.core.tick()
            except Exception:
                log.exception("the 1 s tick failed")

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=10.0)

