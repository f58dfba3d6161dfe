"""ASGI middleware of the coordinator's HTTP side."""

from __future__ import annotations

import json
from typing import Any

from swarmpath.service.protocol import MAX_BODY_BYTES


class BodyLimit:
    """ASGI middleware: request bodies over ``limit`` bytes get a 422 naming the body (checked
    on Content-Length and on the bytes actually received; the body is buffered, at most
    ``limit`` bytes, and replayed to the application).

    ``routes`` gives single routes their own limit: ``{(method, path): (bytes, setting)}``; a
    body over such a limit gets a 413 naming the limit and the setting that raises it."""

    def __init__(self, app: Any, limit: int = MAX_BODY_BYTES,
                 routes: dict[tuple[str, str], tuple[int, str]] | None = None):
        self.app = app
        self.limit = limit
        self.routes = dict(routes or {})

    async def __call__(self, scope: dict[str, Any], receive: Any, send: Any) -> None:
        if scope["type"] != "http" or scope["method"] not in ("POST", "PUT", "PATCH"):
            await self.app(scope, receive, send)
            return
        limit, setting = self.routes.get((scope["method"], scope.get("path", "")),
                                         (self.limit, None))
        length = dict(scope.get("headers") or []).get(b"content-length")
        if length is not None and length.isdigit() and int(length) > limit:
            await self._reject(send, int(length), limit, setting)
            return
        chunks: list[bytes] = []
        size = 0
        while True:
            message = await receive()
            if message["type"] == "http.disconnect":
                return
            body = message.get("body", b"")
            size += len(body)
            if size > limit:
                await self._reject(send, size, limit, setting)
                return
            chunks.append(body)
            if not message.get("more_body", False):
                break
        replayed = False

        async def replay() -> dict[str, Any]:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": b"".join(chunks), "more_body": False}
            return await receive()

        await self.app(scope, replay, send)

    @staticmethod
    async def _reject(send: Any, size: int, limit: int, setting: str | None) -> None:
        msg = f"the request body ({size} bytes or more) exceeds {limit} bytes"
        if setting is not None:
            msg += f" (the coordinator's {setting}; raise it to accept larger uploads)"
        body = json.dumps({"detail": [{
            "loc": ["body"], "type": "body_too_large", "msg": msg,
        }]}).encode()
        headers = [(b"content-type", b"application/json"),
                   (b"content-length", str(len(body)).encode()), (b"connection", b"close")]
        await send({"type": "http.response.start", "status": 422 if setting is None else 413,
                    "headers": headers})
        await send({"type": "http.response.body", "body": body})


# ---------------------------------------------------------------------------- Host and headers
#: The dashboard's pages load only their own scripts, styles and data: no inline script or
#: style, no frame around them (a page elsewhere cannot frame the submit or cancel buttons).
DASHBOARD_CSP = ("default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; "
                 "connect-src 'self'; font-src 'self'; object-src 'none'; base-uri 'none'; "
                 "form-action 'self'; frame-ancestors 'none'")
#: FastAPI's /docs and /redoc pages load Swagger UI / ReDoc from their CDN with an inline
#: script: allowed there only.
DOCS_CSP = ("default-src 'none'; script-src 'self' 'unsafe-inline' https://cdn.jsdelivr.net; "
            "style-src 'self' 'unsafe-inline' https://cdn.jsdelivr.net "
            "https://fonts.googleapis.com; font-src https://fonts.gstatic.com; "
            "img-src 'self' data: https://fastapi.tiangolo.com https://cdn.redoc.ly; "
            "connect-src 'self'; worker-src blob:; frame-ancestors 'none'")
DATA_CSP = "default-src 'none'; frame-ancestors 'none'"  # JSON, text, files: nothing to run
DOCS_PATHS = ("/docs", "/docs/oauth2-redirect", "/redoc")


class SecurityHeaders:
    """ASGI middleware: ``X-Content-Type-Options: nosniff``, ``X-Frame-Options: DENY``,
    ``Referrer-Policy: no-referrer`` and a Content-Security-Policy on every response (the
    dashboard's for HTML pages, FastAPI's docs their own, ``default-src 'none'`` for the rest);
    a header the application set itself is kept."""

    def __init__(self, app: Any):
        self.app = app

    async def __call__(self, scope: dict[str, Any], receive: Any, send: Any) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        path = scope.get("path", "")

        async def with_headers(message: dict[str, Any]) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers") or [])
                have = {k.lower() for k, _v in headers}
                html = any(k.lower() == b"content-type" and v.startswith(b"text/html")
                           for k, v in headers)
                csp = DOCS_CSP if path in DOCS_PATHS else DASHBOARD_CSP if html else DATA_CSP
                for key, value in ((b"x-content-type-options", b"nosniff"),
                                   (b"x-frame-options", b"DENY"),
                                   (b"referrer-policy", b"no-referrer"),
                                   (b"content-security-policy", csp.encode())):
                    if key not in have:
                        headers.append((key, value))
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, with_headers)


def host_name(header: str) -> str:
    """The name part of a Host header (``[::1]:8000`` -> ``::1``), lower case, no final dot."""
    header = header.strip().lower()
    if header.startswith("["):
        return header[1:].split("]", 1)[0]
    if header.count(":") == 1:
        header = header.split(":", 1)[0]
    return header.rstrip(".")


def _is_ip(name: str) -> bool:
    import ipaddress

    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


def allowed_hosts(bind: str, extra: list[str] | tuple[str, ...] = ()) -> list[str]:
    """The Host names a coordinator bound to ``bind`` answers: loopback's names, the bound
    address, any IP address when bound to every interface (``*ip``), and ``extra`` (the names
    a deployment reaches it by; ``*``: any, no check). A DNS-rebinding page can only send a
    name of its own, never an address, so addresses are never a risk."""
    bind = host_name(bind)
    names = ["localhost", "127.0.0.1", "::1"]
    if bind in ("0.0.0.0", "::", ""):
        names.append("*ip")
    elif bind not in names:
        names.append(bind)
    for name in extra:
        name = host_name(name) if name.strip() != "*" else "*"
        if name and name not in names:
            names.append(name)
    return names


class HostCheck:
    """ASGI middleware: a request whose Host header is not one of ``names`` (see
    :func:`allowed_hosts`) gets a 400 naming the setting that admits it. Issue 25: any Host was
    served, so a page of evil.example whose name was rebound to 127.0.0.1 could submit jobs
    with the default no-token configuration."""

    def __init__(self, app: Any, names: list[str]):
        self.app = app
        self.names = set(names)
        self.any_ip = "*ip" in self.names
        self.anything = "*" in self.names

    def allows(self, header: str | None) -> bool:
        if self.anything or header is None:  # no Host at all: not a browser's request
            return True
        name = host_name(header)
        return name in self.names or (self.any_ip and _is_ip(name))

    async def __call__(self, scope: dict[str, Any], receive: Any, send: Any) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        raw = dict(scope.get("headers") or []).get(b"host")
        header = raw.decode("latin-1") if raw is not None else None
        if self.allows(header):
            await self.app(scope, receive, send)
            return
        shown = (header or "")[:100]
        body = json.dumps({"detail": (
            f"Host {shown!r} is not a name of this coordinator (it answers "
            f"{', '.join(sorted(n for n in self.names if n != '*ip'))}"
            f"{' and any IP address' if self.any_ip else ''}); a deployment reached by "
            "another name adds it with --allowed-host NAME or SWARMPATH_ALLOWED_HOSTS")}
        ).encode()
        await send({"type": "http.response.start", "status": 400, "headers": [
            (b"content-type", b"application/json"),
            (b"content-length", str(len(body)).encode())]})
        await send({"type": "http.response.body", "body": body})
