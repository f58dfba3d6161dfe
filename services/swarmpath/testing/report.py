"""The result of a conformance check: one verdict per property, and figures shown as information."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field


class ConformanceError(AssertionError):
    """Raised by ``check_*`` when a property fails; the message names every failing one."""

    def __init__(self, report: Report):
        self.report = report
        lines = [f"{report.kind} {report.name!r} fails {len(report.failures)} "
                 f"conformance propert{'y' if len(report.failures) == 1 else 'ies'}:"]
        lines += [f"  {p.name}: {p.detail}" for p in report.failures]
        super().__init__("\n".join(lines))


@dataclass
class Property:
    name: str
    ok: bool
    detail: str = ""


@dataclass
class Report:
    kind: str  # optimizer, function, planner
    name: str
    properties: list[Property] = field(default_factory=list)
    #: figures printed as information, never a verdict (the origin-bias audit)
    info: dict[str, str] = field(default_factory=dict)

    @property
    def failures(self) -> list[Property]:
        return [p for p in self.properties if not p.ok]

    @property
    def ok(self) -> bool:
        return not self.failures

    def check(self, name: str, test: Callable[[], str | None]) -> None:
        """Run one property: ``test()`` returns None when it holds, else why it does not; an
        exception it raises is a failure of that property too (its type and message)."""
        try:
            problem = test()
        except Exception as exc:  # the property could not even be tested: it fails, named
            problem = f"raised {type(exc).__name__}: {exc}"
        self.properties.append(Property(name, problem is None, problem or ""))

    def raise_for_failures(self) -> Report:
        if self.failures:
            raise ConformanceError(self)
        return self

    def lines(self) -> list[str]:
        out = [f"{'ok  ' if p.ok else 'FAIL'} {p.name}" + (f": {p.detail}" if p.detail else "")
               for p in self.properties]
        out += [f"info {key}: {value}" for key, value in self.info.items()]
        return out

    def to_dict(self) -> dict[str, object]:
        return {"kind": self.kind, "name": self.name, "ok": self.ok,
                "properties": [{"name": p.name, "ok": p.ok, "detail": p.detail}
                               for p in self.properties],
                "info": dict(self.info)}
