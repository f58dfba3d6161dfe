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
