"""Maps uploaded with ``POST /maps``: the upload as sent, the scenario imported from it and the
pairs of the ``.scen`` that came with it."""

from __future__ import annotations

import json
import secrets
import time
from typing import Any

from swarmpath.service.map_pairs import scen_info
from swarmpath.service.store.base import StoreBase, _dumps


class MapsMixin(StoreBase):
    def add_map(self, name: str, fmt: str, source: dict[str, Any], scenario: dict[str, Any],
                now: float | None = None, pairs: dict[str, Any] | None = None) -> str:
        """Store an imported map durably (committed before it returns) with the pairs of its
        ``.scen`` when it came with one (:func:`swarmpath.service.map_pairs.scen_rows`);
        returns its new id."""
        map_id = f"map-{secrets.token_hex(6)}"
        with self._tx() as db:
            db.execute(
                "INSERT INTO maps (id, name, format, source, scenario, created) "
                "VALUES (?, ?, ?, ?, ?, ?)",
                (map_id, name, fmt, _dumps(source), _dumps(scenario),
                 time.time() if now is None else now),
            )
            if pairs is not None:
                db.execute("INSERT INTO map_scen (map_id, pairs, info) VALUES (?, ?, ?)",
                           (map_id, _dumps(pairs), _dumps(scen_info(pairs))))
        return map_id

    def map_pairs(self, map_id: str) -> dict[str, Any] | None:
        """The stored pairs of a map's ``.scen``, or None (no such map, or none uploaded)."""
        with self._read() as db:
            row = db.execute("SELECT pairs FROM map_scen WHERE map_id = ?",
                             (map_id,)).fetchone()
        return None if row is None else dict(json.loads(row[0]))

    def map_scenario(self, map_id: str) -> dict[str, Any] | None:
        """The scenario (JSON object) of an uploaded map, or None for an unknown id."""
        with self._read() as db:
            row = db.execute("SELECT scenario FROM maps WHERE id = ?", (map_id,)).fetchone()
        return None if row is None else dict(json.loads(row[0]))

    def map_info(self, map_id: str) -> dict[str, Any] | None:
        with self._read() as db:
            row = db.execute("SELECT id, name, format, scenario, created FROM maps WHERE id = ?",
                             (map_id,)).fetchone()
            if row is None:
                return None
            return dict(_info(row, with_scenario=True), scen=_scen(db, map_id))

    def list_maps(self, limit: int = 100, offset: int = 0) -> list[dict[str, Any]]:
        """Uploaded maps, newest first (without their scenarios)."""
        with self._read() as db:
            rows = db.execute(
                "SELECT id, name, format, scenario, created FROM maps "
                "ORDER BY created DESC, id LIMIT ? OFFSET ?", (limit, offset)).fetchall()
            return [dict(_info(r, with_scenario=False), scen=_scen(db, r["id"])) for r in rows]


def _scen(db: Any, map_id: str) -> dict[str, Any] | None:
    """``{"pairs", "buckets": {bucket: pairs}}`` of a map's .scen, or None without one."""
    row = db.execute("SELECT info FROM map_scen WHERE map_id = ?", (map_id,)).fetchone()
    return None if row is None else dict(json.loads(row[0]))


def _info(row: Any, with_scenario: bool) -> dict[str, Any]:
    scenario = json.loads(row["scenario"])
    grid = scenario.get("grid") or {}
    frame = str(grid.get("frame") or "scenario")
    ox, oy = (float(v) for v in grid.get("origin") or (0.0, 0.0))
    # positions in the map's own frame (a nav2 map's YAML origin honoured), as a job's
    # {"map": id, "start", "goal"} takes them
    out = {"id": row["id"], "name": row["name"], "format": row["format"],
           "created": row["created"], "size": scenario["size"], "frame": frame,
           "origin": [ox, oy],
           "start": [scenario["start"][0] + ox, scenario["start"][1] + oy],
           "goal": [scenario["goal"][0] + ox, scenario["goal"][1] + oy],
           "obstacles": len(scenario.get("obstacles", ()))}
    if with_scenario:
        out["scenario"] = scenario
    return out
