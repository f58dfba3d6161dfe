"""The numba options of a compiled helper that borrows its caller's arrays: compiled without
reference counting (``@njit(cache=True, **NO_REFCOUNT)``; rule 7 of this package's docstring
says when and why). A dict typed ``Any`` because numba's stubs do not list ``_nrt``."""

from typing import Any

NO_REFCOUNT: dict[str, Any] = {"_nrt": False}
