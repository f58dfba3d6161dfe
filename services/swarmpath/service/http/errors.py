"""422 answers: one detail item per problem, ``loc`` down to the field (inside an inline
scenario: ``["body", "maps", 0, "obstacles", 2, "radius"]``), messages in plain words
(:func:`swarmpath.errors.plain_message`), "did you mean" for near-miss names."""

from __future__ import annotations

from typing import Any

from swarmpath.errors import plain_message
from swarmpath.service.protocol import BenchmarkJobSpec, FieldProblems, MapJobSpec

#: Tags of the body unions (job specs, map uploads): pydantic puts them in ``loc``; they are not
#: fields of the body.
_UNION_TAGS = ("benchmark", "map", "nav2", "movingai")


def _spec_fields() -> list[str]:
    return list(dict.fromkeys([*BenchmarkJobSpec.model_fields, *MapJobSpec.model_fields]))


def clean_loc(loc: Any) -> list[Any]:
    """Drop what is not a field: the body's union tag (job kind, upload format) and the member
    labels of unions
    (``str``, ``dict[str,any]``)."""
    parts = list(loc)
    out: list[Any] = []
    for i, p in enumerate(parts):
        if i == 1 and parts[0] == "body" and p in _UNION_TAGS:
            continue
        if isinstance(p, str) and ("[" in p or p in ("str", "int", "float", "bool")):
            continue
        out.append(p)
    return out


def validation_detail(errors: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """pydantic/FastAPI errors -> ``[{"loc", "msg", "type"}]``, one problem per item."""
    items: list[dict[str, Any]] = []
    for e in errors:
        loc = clean_loc(e.get("loc", ()))
        kind = str(e.get("type", ""))
        problem = (e.get("ctx") or {}).get("error")
        if isinstance(problem, FieldProblems):
            # each its own problem: never merged with another at the same place
            items += [{"loc": loc + list(sub), "msg": msg, "type": kind, "own": True}
                      for sub, msg in problem.problems]
            continue
        if kind in ("union_tag_invalid", "union_tag_not_found") and loc == ["body"]:
            tag = str((e.get("ctx") or {}).get("discriminator", "kind")).strip("'")
            loc = ["body", tag]
        items.append({"loc": loc, "msg": plain_message(e, _spec_fields()), "type": kind})
    merged: dict[tuple[str, ...], dict[str, Any]] = {}
    for n, item in enumerate(items):  # a union's members fail at the same place: "a or b"
        key = tuple(str(p) for p in item["loc"])
        if item.pop("own", False):
            merged[(*key, f"#{n}")] = item
            continue
        if key in merged:
            first = merged[key]
            if item["msg"] not in first["msg"]:
                extra = item["msg"].removeprefix("must be ")
                first["msg"] += f" or {extra}"
            continue
        merged[key] = dict(item)
    return list(merged.values())
