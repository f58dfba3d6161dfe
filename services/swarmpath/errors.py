"""Validation errors in plain words: pydantic's error dicts (``type``, ``loc``, ``ctx``) become
one short message each, without pydantic's wording ("Input should be a valid tuple"). Used by
the scenario reader and by the coordinator's 422 answers; pure (works on the dicts)."""

from __future__ import annotations

import re
import reprlib
from typing import Any

_BRIEF = reprlib.Repr()
_BRIEF.maxlevel = 2
_BRIEF.maxlist = _BRIEF.maxtuple = _BRIEF.maxdict = _BRIEF.maxset = 4
_BRIEF.maxstring = _BRIEF.maxother = _BRIEF.maxlong = 60


def brief(value: Any, limit: int = 80) -> str:
    """``repr`` of a value a user sent, bounded whatever it is: two levels of nesting, four items
    per container, ``limit`` characters. A plain ``{value!r}`` of a YAML document's shared
    aliases expands all of them (issue 25: 2 KB of YAML, 10 GB of memory)."""
    try:
        text = _BRIEF.repr(value)
    except Exception:  # an int of more than 4,300 digits, a repr that raises
        text = f"<a {type(value).__name__} too long to show>"
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _g(v: Any) -> str:
    return f"{v:g}" if isinstance(v, int | float) and not isinstance(v, bool) else repr(v)


def _items(n: Any) -> str:
    return f"{n} item" + ("" if n == 1 else "s")


def near_miss(given: Any, expected: Any) -> str:
    """``" (did you mean 'omni'?)"`` when ``given`` is a near miss of one of the quoted names in
    pydantic's ``expected`` text (``"'diff-drive', 'turtlebot3-burger' or 'omni'"``), else
    ``""``."""
    from swarmpath.names import did_you_mean

    if not isinstance(given, str):
        return ""
    return did_you_mean(given, re.findall(r"'([^']*)'", str(expected)))


def plain_message(err: dict[str, Any], fields: list[str] | None = None) -> str:
    """One error dict -> its message. ``fields``: the valid field names, for "did you mean" on
    an unknown field."""
    kind = str(err.get("type", ""))
    ctx = err.get("ctx") or {}
    msg = str(err.get("msg", ""))
    if kind == "missing":
        return "required"
    if kind == "extra_forbidden":
        from swarmpath.names import did_you_mean

        loc = err.get("loc") or ("",)
        return "unknown field" + (did_you_mean(str(loc[-1]), fields) if fields else "")
    if kind in ("int_type", "int_parsing", "int_from_float", "int_parsing_size"):
        return "must be an integer"
    if kind in ("float_type", "float_parsing"):
        return "must be a number"
    if kind == "finite_number":
        return "must be a finite number"
    if kind in ("bool_type", "bool_parsing"):
        return "must be true or false"
    if kind == "string_type":
        return "must be a string"
    if kind in ("list_type", "tuple_type", "set_type"):
        return "must be a list"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        return "must be an object"
    if kind == "greater_than":
        return f"must be > {_g(ctx.get('gt'))}"
    if kind == "greater_than_equal":
        return f"must be >= {_g(ctx.get('ge'))}"
    if kind == "less_than":
        return f"must be < {_g(ctx.get('lt'))}"
    if kind == "less_than_equal":
        return f"must be <= {_g(ctx.get('le'))}"
    if kind == "too_short":
        return f"needs at least {_items(ctx.get('min_length'))}"
    if kind == "too_long":
        return f"allows at most {_items(ctx.get('max_length'))}"
    if kind == "string_too_short":
        return "must not be empty"
    if kind == "string_too_long":
        return f"allows at most {ctx.get('max_length')} characters"
    if kind == "string_pattern_mismatch":
        return f"must match {ctx.get('pattern')}"
    if kind == "literal_error":
        return f"must be {ctx.get('expected')}" + near_miss(err.get("input"), ctx.get("expected"))
    if kind == "enum":
        return f"must be {ctx.get('expected')}"
    if kind == "union_tag_invalid":
        return (f"must be one of {ctx.get('expected_tags')}, got {ctx.get('tag')!r}"
                + near_miss(ctx.get("tag"), ctx.get("expected_tags")))
    if kind == "union_tag_not_found":
        return f"required: {ctx.get('discriminator', 'a tag')}"
    if kind == "json_invalid":
        return f"not valid JSON: {ctx.get('error', msg)}"
    if kind in ("value_error", "assertion_error"):
        for prefix in ("Value error, ", "Assertion failed, "):
            if msg.startswith(prefix):
                return msg[len(prefix):]
    return msg
