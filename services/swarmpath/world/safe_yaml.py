"""YAML written by users (nav2 map files, scenario files, uploads), read so that no document can
stall the reader or exhaust its memory.

PyYAML's safe loader builds an alias (``*name``) as a second reference to the anchored value, so
a 2 KB document of nine nested anchor levels is a structure of 9**9 values that costs nothing to
load and hangs whatever walks it (a ``repr`` in an error message took a coordinator to 10 GB,
issue 25). A document nested 10,000 levels deep makes the composer recurse until Python's
recursion limit. :func:`load_yaml` composes the node graph first and refuses, before any value is
built:

* nesting deeper than ``max_depth`` levels (64: a nav2 map or a scenario has 4);
* a document that would expand into more than ``max_values`` values, aliases counted as often as
  they are used (1,000,000: a 5,000-obstacle scenario has about 60,000);
* an alias inside its own anchor (a recursive structure);
* an integer of more than 4,300 digits (Python's conversion limit).

Each refusal is a :class:`YamlLimitError`, a ``yaml.YAMLError``, so readers report it as they
report a syntax error.
"""

from __future__ import annotations

from typing import Any

import yaml

MAX_DEPTH = 64
MAX_VALUES = 1_000_000


class YamlLimitError(yaml.YAMLError):
    """A document over a bound of :func:`load_yaml` (the message names the bound)."""


class _BoundedLoader(yaml.SafeLoader):
    max_depth = MAX_DEPTH
    _depth = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self._depth >= self.max_depth:
            mark = self.peek_event().start_mark
            raise YamlLimitError(
                f"nests deeper than {self.max_depth} levels (line {mark.line + 1})")
        self._depth += 1
        try:
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def _expanded_size(root: yaml.Node, limit: int) -> int:
    """Values the node graph stands for once every alias is expanded (shared nodes counted once
    per use, computed once per node); raises on a cycle or beyond ``limit``."""
    sizes: dict[int, int] = {}
    open_nodes: set[int] = set()

    def size(node: yaml.Node) -> int:
        key = id(node)
        if key in sizes:
            return sizes[key]
        if key in open_nodes:
            raise YamlLimitError("an alias refers to a value that contains it (a recursive "
                                 f"structure, line {node.start_mark.line + 1})")
        open_nodes.add(key)
        n = 1
        if isinstance(node, yaml.SequenceNode):
            n += sum(size(child) for child in node.value)
        elif isinstance(node, yaml.MappingNode):
            n += sum(size(k) + size(v) for k, v in node.value)
        open_nodes.discard(key)
        if n > limit:
            raise YamlLimitError(
                f"expands to more than {limit:,} values through its aliases (*name), "
                f"line {node.start_mark.line + 1}")
        sizes[key] = n
        return n

    return size(root)


def load_yaml(text: str, *, max_depth: int = MAX_DEPTH, max_values: int = MAX_VALUES) -> Any:
    """``yaml.safe_load(text)`` within the bounds of the module docstring."""
    loader = _BoundedLoader(text)
    loader.max_depth = max_depth
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_size(node, max_values)
        try:
            return loader.construct_document(node)
        except ValueError as exc:  # int() of more than 4,300 digits
            raise YamlLimitError(f"a value cannot be read: {exc}") from None
    except RecursionError:  # pragma: no cover - the depth bound comes first
        raise YamlLimitError(f"nests deeper than {max_depth} levels") from None
    finally:
        loader.dispose()
