"""Which login speaks for which worker: a worker id belongs to a Zenoh login, and its lease
requests prove that login (issue 25: under ``swarmpath up`` a second valid login leased under
another worker's id, public in ``GET /workers``, and its made-up results were stored as that
worker's).

Zenoh tells the application nothing about who sent a query, so the binding is made here, from
what only the login's holder and the coordinator know (the coordinator reads the same
``user:password`` dictionary its router authenticates sessions with):

* **Ownership by name.** Worker id ``W`` belongs to the login ``L`` that is ``W`` itself or the
  longest login ``L`` with ``W`` starting ``L-`` (``lab`` owns ``lab-node3-812``, ``lab-gpu``
  owns ``lab-gpu-1`` even when ``lab`` is a login too). ``swarmpath up`` gives each local worker a
  login of its own named by its id; a worker started with ``--user L`` is ``L-HOST-PID`` unless
  ``--id`` says otherwise. A worker id no login owns is refused.
* **Proof.** A lease request carries ``login``, ``issued`` and ``proof`` = HMAC-SHA256(the
  login's password, ``lease-request\\n<worker>\\n<login>\\n<issued>``). ``issued`` (the worker's
  clock in nanoseconds, made strictly increasing) must exceed the last one accepted for that
  worker, so a copied request is not accepted twice.

Leases (and with them the capabilities that results, progress and scenario queries must prove)
are granted only on a proven request, so every stored result was computed under the login that
owns its worker id. A coordinator without a dictionary (``--insecure``, or mutual TLS whose
certificate names Zenoh does not pass on) checks nothing here.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import time
from pathlib import Path

PURPOSE = b"lease-request"


class LoginFileError(ValueError):
    """A dictionary file that is not ``user:password`` lines."""


def read_logins(path: str | os.PathLike[str]) -> dict[str, str]:
    """``{user: password}`` of a Zenoh usrpwd dictionary (one ``user:password`` per line)."""
    logins: dict[str, str] = {}
    for n, raw in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), start=1):
        line = raw.strip()
        if not line:
            continue
        user, sep, password = line.partition(":")
        if not sep or not user or not password:
            raise LoginFileError(f"{path}: line {n} is not a user:password line")
        logins[user] = password
    return logins


def write_logins(path: Path, logins: dict[str, str]) -> None:
    """The dictionary file, readable by its owner only (0600 from its creation on)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as f:
        f.write("".join(f"{user}:{password}\n" for user, password in logins.items()))
    os.chmod(path, 0o600)


def new_password() -> str:
    return secrets.token_urlsafe(24)


def owner(worker: str, logins: dict[str, str] | set[str]) -> str | None:
    """The login that owns worker id ``worker`` (the rule in the module docstring), or None."""
    if worker in logins:
        return worker
    best: str | None = None
    for login in logins:
        if worker.startswith(login + "-") and (best is None or len(login) > len(best)):
            best = login
    return best


def id_for(login: str, worker_id: str | None, default: str) -> str:
    """A worker's id under ``login``: ``worker_id`` when given (it must be owned by the login),
    else ``<login>-<default>``; raises ValueError naming the rule."""
    if worker_id is None:
        return f"{login}-{default}"
    if owner(worker_id, {login}) != login:
        raise ValueError(f"{worker_id!r} is not an id of login {login!r}: under a login a worker "
                         f"id is the login itself or starts with '{login}-'")
    return worker_id


def request_proof(password: str, worker: str, login: str, issued: int) -> str:
    message = b"\n".join((PURPOSE, worker.encode(), login.encode(), str(int(issued)).encode()))
    return hmac.new(password.encode(), message, hashlib.sha256).hexdigest()


class Issuer:
    """A worker's ``issued`` values: its clock in nanoseconds, strictly increasing."""

    def __init__(self) -> None:
        self._last = 0

    def __call__(self) -> int:
        self._last = max(time.time_ns(), self._last + 1)
        return self._last


def refusal(worker: str, login: str, issued: int, proof: str,
            logins: dict[str, str]) -> str | None:
    """Why a lease request may not speak for ``worker`` (None when it may). The reasons name
    what is wrong, never a password."""
    if not login:
        return "this coordinator requires a login: give the worker --user/--password"
    password = logins.get(login)
    if password is None:
        return f"unknown login {login!r}"
    if owner(worker, logins) != login:
        return (f"worker id {worker!r} does not belong to login {login!r} (a worker id is its "
                f"login, or starts with '{login}-')")
    if not proof or not hmac.compare_digest(request_proof(password, worker, login, issued),
                                            proof):
        return f"the request is not proven by the password of login {login!r}"
    return None
