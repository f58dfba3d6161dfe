"""The Zenoh logins of ``swarmpath up`` and ``swarmpath coordinator`` (issue 25: a coordinator
without ``--auth-dictionary`` let any local process lease work and store made-up numbers).

* ``up``: a login per local worker, made at each start and named by the worker's id (its id
  belongs to it, :mod:`swarmpath.service.identity`), plus the logins of ``--auth-dictionary``.
* ``coordinator``: with neither ``--auth-dictionary`` nor mutual TLS in ``--zenoh-config`` it
  makes one login ``local`` in ``DATA/zenoh-users.txt`` (0600; kept across restarts, so its
  workers reconnect) for workers started with ``--login-file DATA/zenoh-users.txt``; ``--insecure``
  runs without any, and says so loudly.

Both give the router worker access control for every login (a login may do only what a worker
does), merged under what ``--zenoh-config`` says.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from swarmpath.cli.core import InputError
from swarmpath.service.identity import LoginFileError, new_password, read_logins, write_logins

USERS_FILE = "zenoh-users.txt"
STANDALONE_LOGIN = "local"


def extra_logins(path: Path | None, option: str = "--auth-dictionary") -> dict[str, str]:
    if path is None:
        return {}
    if not path.is_file():
        raise InputError(option, f"{str(path)!r} does not exist")
    try:
        return read_logins(path)
    except (LoginFileError, UnicodeDecodeError, OSError) as exc:
        raise InputError(option, str(exc)) from None


def local_logins(data: Path, ids: list[str], extra: Path | None
                 ) -> tuple[list[tuple[str, str]], Path]:
    """A fresh login for each local worker (named by its id) written with the logins of
    ``extra`` to DATA/zenoh-users.txt (0600); the local ones, and the file."""
    others = extra_logins(extra)
    clash = sorted(set(ids) & set(others))
    if clash:
        raise InputError("--auth-dictionary", f"{clash[0]!r} is the id of a local worker")
    local = {worker: new_password() for worker in ids}
    path = data / USERS_FILE
    write_logins(path, {**local, **others})
    return list(local.items()), path


def standalone_login(data: Path) -> Path:
    """DATA/zenoh-users.txt with the login ``local`` (made once; an existing file is kept)."""
    path = data / USERS_FILE
    if path.is_file():
        try:
            if read_logins(path):
                return path
        except (LoginFileError, UnicodeDecodeError):
            pass
    write_logins(path, {STANDALONE_LOGIN: new_password()})
    return path


def login_file(path: Path) -> tuple[str, str]:
    """The first ``user:password`` of a login file (``swarmpath worker --login-file``)."""
    logins = extra_logins(path, "--login-file")
    if not logins:
        raise InputError("--login-file", f"{path}: no user:password line")
    return next(iter(logins.items()))


def mutual_tls(extra: dict[str, Any] | None) -> bool:
    """Whether ``--zenoh-config`` makes the router require client certificates."""
    tls = ((extra or {}).get("transport") or {}).get("link", {}).get("tls") or {}
    return bool(tls.get("enable_mtls"))


def with_access_control(prefix: str, users: list[str], extra: dict[str, Any] | None
                        ) -> dict[str, Any]:
    """Worker access control for ``users``, with ``extra`` (--zenoh-config) merged over it."""
    from swarmpath.service.zenoh_config import _merge, worker_access_control

    conf: dict[str, Any] = {"access_control": worker_access_control(prefix, usernames=users)}
    return _merge(conf, extra or {})
