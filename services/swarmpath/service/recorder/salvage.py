"""Reading what a killed process left in a job's unfinished ``.part`` MCAP file."""

from __future__ import annotations

import json
import logging
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from mcap.exceptions import McapError
from mcap.reader import NonSeekingReader

log = logging.getLogger(__name__)


def salvage_messages(
    path: Path | str, topics: Iterable[str] | None = None
) -> list[tuple[str, Any]]:
    """(topic, decoded JSON) of every message readable from a possibly unfinished MCAP file,
    in file order: streams records until the cut (make_reader's seeking reader needs a footer)."""
    out: list[tuple[str, Any]] = []
    with open(path, "rb") as f:
        reader = NonSeekingReader(f, validate_crcs=True)
        try:
            for _schema, channel, message in reader.iter_messages(
                topics=list(topics) if topics is not None else None, log_time_order=False
            ):
                out.append((channel.topic, json.loads(message.data)))
        except (McapError, EOFError, ValueError, OSError) as exc:
            log.info("stopped reading %s at the cut: %s", path, exc)
    return out
