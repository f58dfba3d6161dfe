"""The service's process commands: ``up`` (a coordinator and local workers), ``coordinator`` and
``worker``; the REST client commands are in :mod:`swarmpath.cli.service`.

Heavy imports (fastapi, uvicorn, zenoh) stay inside the command functions.
"""

from __future__ import annotations

import logging
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Annotated, Any

import typer

from swarmpath.cli.core import InputError, app

DEFAULT_DATA = "swarmpath-data"
DEFAULT_ZENOH = "tcp/127.0.0.1:7447"
DEFAULT_HTTP = "127.0.0.1:8000"


def _logging(level: str) -> None:
    logging.basicConfig(
        level=getattr(logging, level.upper(), logging.INFO),
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
        stream=sys.stderr,
    )


def parse_http(value: str, option: str = "--http") -> tuple[str, int]:
    """'127.0.0.1:8000' -> ('127.0.0.1', 8000)."""
    host, sep, port = value.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise InputError(option, f"{value!r} is not HOST:PORT (e.g. 127.0.0.1:8000)")
    return host.strip("[]"), int(port)


def _endpoints(values: list[str] | None, option: str, default: str) -> list[str]:
    from swarmpath.service.zenoh_config import check_endpoint

    out = []
    for v in values or [default]:
        try:
            out.append(check_endpoint(v))
        except ValueError as exc:
            raise InputError(option, str(exc)) from None
    return out


def _connectable(listen: str) -> str:
    """Where local workers connect for a listen endpoint (0.0.0.0 / [::] -> loopback)."""
    proto, _, rest = listen.partition("/")
    host, _, port = rest.rpartition(":")
    if host in ("0.0.0.0", "[::]", "::"):
        host = "127.0.0.1"
    return f"{proto}/{host}:{port}"


def _extra(path: Path | None, option: str) -> dict[str, Any] | None:
    from swarmpath.service.zenoh_config import load_extra

    try:
        return load_extra(path)
    except (OSError, ValueError) as exc:
        raise InputError(option, str(exc)) from None


def _coordinator_settings(
    data: Path, zenoh: list[str] | None, prefix: str, lease_seconds: float, shm: bool,
    auth_dictionary: Path | None, zenoh_config: Path | None,
) -> Any:
    from swarmpath.service.coordinator import CoordinatorSettings
    from swarmpath.service.protocol import Keys

    try:
        Keys(prefix)
    except ValueError as exc:
        raise InputError("--prefix", str(exc)) from None
    if lease_seconds <= 0:
        raise InputError("--lease-seconds", "must be positive")
    if auth_dictionary is not None and not auth_dictionary.is_file():
        raise InputError("--auth-dictionary", f"{str(auth_dictionary)!r} does not exist")
    return CoordinatorSettings(
        data_dir=data, zenoh_listen=_endpoints(zenoh, "--zenoh", DEFAULT_ZENOH), prefix=prefix,
        lease_seconds=lease_seconds, shm=shm,
        dictionary_file=str(auth_dictionary) if auth_dictionary else None,
        zenoh_extra=_extra(zenoh_config, "--zenoh-config"), recorder_process=True,
    )


def _serve(app_: Any, http: str, log_level: str) -> None:
    import uvicorn

    host, port = parse_http(http)
    config = uvicorn.Config(app_, host=host, port=port, log_level=log_level.lower(),
                            access_log=log_level.lower() == "debug", lifespan="on",
                            timeout_graceful_shutdown=5)
    server = uvicorn.Server(config)
    handle_exit = server.handle_exit

    def stopping(sig: int, frame: Any) -> None:  # open dashboard event streams end at once
        app_.state.stopping = True
        handle_exit(sig, frame)

    server.handle_exit = stopping  # type: ignore[method-assign]
    server.run()
    if not server.started:
        typer.echo(f"swarmpath: error: could not serve HTTP on {http}", err=True)
        raise typer.Exit(1)


# ------------------------------------------------------------------------------- processes
ZenohOpt = Annotated[
    list[str] | None,
    typer.Option("--zenoh", help="Zenoh listen endpoint(s).", show_default=DEFAULT_ZENOH),
]
DataOpt = Annotated[Path, typer.Option("--data", help="Data directory (SQLite queue, MCAP files).")]
HttpOpt = Annotated[str, typer.Option("--http", help="HTTP listen address HOST:PORT.")]
PrefixOpt = Annotated[str, typer.Option("--prefix", help="Key-expression prefix.")]
LogOpt = Annotated[str, typer.Option("--log-level", help="debug, info, warning, error.")]
LeaseOpt = Annotated[
    float, typer.Option("--lease-seconds", help="Requeue a lease after this long without news.")
]
ShmOpt = Annotated[bool, typer.Option("--shm", help="Enable Zenoh shared memory (off by default).")]
StackingOpt = Annotated[
    bool, typer.Option("--stacking/--no-stacking",
                       help="Run a bundle's leases that differ only in the function as one batch.")
]
ZConfOpt = Annotated[
    Path | None, typer.Option("--zenoh-config", help="JSON file of extra Zenoh settings.")
]


@app.command()
def coordinator(
    http: HttpOpt = DEFAULT_HTTP,
    zenoh: ZenohOpt = None,
    data: DataOpt = Path(DEFAULT_DATA),
    prefix: PrefixOpt = "swarmpath",
    lease_seconds: LeaseOpt = 30.0,
    auth_dictionary: Annotated[
        Path | None,
        typer.Option("--auth-dictionary",
                     help="Zenoh user/password file (user:password lines): workers must log in."),
    ] = None,
    shm: ShmOpt = False,
    zenoh_config: ZConfOpt = None,
    log_level: LogOpt = "info",
) -> None:
    """Run the coordinator: REST API, job queue and the Zenoh router (no local workers)."""
    parse_http(http)
    settings = _coordinator_settings(data, zenoh, prefix, lease_seconds, shm, auth_dictionary,
                                     zenoh_config)
    _logging(log_level)
    from swarmpath.service.coordinator import create_app

    _serve(create_app(settings), http, log_level)


@app.command()
def worker(
    connect: Annotated[
        list[str] | None,
        typer.Option("--connect",
                     help="Coordinator's Zenoh endpoint(s).", show_default=DEFAULT_ZENOH),
    ] = None,
    slots: Annotated[int, typer.Option("--slots", help="Leases executed concurrently.")] = 1,
    worker_id: Annotated[
        str | None, typer.Option("--id", help="Worker id.", show_default="HOST-PID")
    ] = None,
    prefix: PrefixOpt = "swarmpath",
    user: Annotated[
        str | None, typer.Option("--user", envvar="SWARMPATH_ZENOH_USER", help="Zenoh user.")
    ] = None,
    password: Annotated[
        str | None,
        typer.Option("--password", envvar="SWARMPATH_ZENOH_PASSWORD",
                     help="Zenoh password (prefer the environment variable)."),
    ] = None,
    threads: Annotated[
        bool, typer.Option("--threads", help="Run leases in threads, not child processes.")
    ] = False,
    grace: Annotated[
        float, typer.Option("--grace", help="On SIGTERM, let running leases finish this long.")
    ] = 10.0,
    max_leases: Annotated[
        int, typer.Option("--max-leases",
                          help="Leases per pull: small cells come bundled up to this many.")
    ] = 32,
    prefetch: Annotated[
        int, typer.Option("--prefetch",
                          help="Bundles pulled ahead of free slots (0: pull only when idle).")
    ] = 1,
    stacking: StackingOpt = True,
    exit_with_parent: Annotated[int | None, typer.Option(hidden=True)] = None,
    shm: ShmOpt = False,
    zenoh_config: ZConfOpt = None,
    log_level: LogOpt = "info",
) -> None:
    """Run a worker: pull runs from the coordinator, execute them, report the results."""
    from swarmpath.service.protocol import ID_PATTERN, MAX_BUNDLE_LEASES, Keys
    from swarmpath.service.worker import WorkerSettings, run_worker

    endpoints = _endpoints(connect, "--connect", DEFAULT_ZENOH)
    if not 1 <= slots <= 256:
        raise InputError("--slots", f"{slots} is not in [1, 256]")
    try:
        keys = Keys(prefix)
        if worker_id is not None:
            keys.worker_token(worker_id)
    except ValueError as exc:
        option = "--prefix" if "prefix" in str(exc) else "--id"
        raise InputError(option, f"{exc} (ids match {ID_PATTERN})") from None
    if bool(user) != bool(password):
        raise InputError("--password" if user else "--user", "user and password go together")
    if grace < 0:
        raise InputError("--grace", "must be >= 0")
    if not 1 <= max_leases <= MAX_BUNDLE_LEASES:
        raise InputError("--max-leases", f"{max_leases} is not in [1, {MAX_BUNDLE_LEASES}]")
    if not 0 <= prefetch <= 16:
        raise InputError("--prefetch", f"{prefetch} is not in [0, 16]")
    settings = WorkerSettings(
        connect=endpoints, prefix=prefix, slots=slots, worker_id=worker_id,
        executor="thread" if threads else "process", user=user, password=password, shm=shm,
        zenoh_extra=_extra(zenoh_config, "--zenoh-config"), grace_seconds=grace,
        exit_with_parent=exit_with_parent, max_leases=max_leases, prefetch=prefetch,
        stacking=stacking,
    )
    _logging(log_level)
    raise typer.Exit(run_worker(settings))


class LocalWorkers:
    """The worker subprocesses of ``swarmpath up`` (fork+exec'd, so nothing of Zenoh is shared)."""

    def __init__(self, n: int, connect: str, prefix: str, slots: int, log_level: str,
                 login: tuple[str, str] | None = None, stacking: bool = True):
        self.n, self.connect, self.prefix, self.slots = n, connect, prefix, slots
        self.stacking = stacking
        self.log_level = log_level
        self.login = login  # (user, password), handed over in the environment, never in argv
        self.procs: list[subprocess.Popen[bytes]] = []

    def start(self) -> None:
        for i in range(self.n):
            cmd = [
                sys.executable, "-m", "swarmpath.cli", "worker", "--connect", self.connect,
                "--prefix", self.prefix, "--slots", str(self.slots),
                "--exit-with-parent", str(os.getpid()), "--log-level", self.log_level,
                "--id", f"{_host()}-{os.getpid()}-w{i}",
                *([] if self.stacking else ["--no-stacking"]),
            ]
            env = dict(os.environ)
            if self.login is not None:
                env["SWARMPATH_ZENOH_USER"], env["SWARMPATH_ZENOH_PASSWORD"] = self.login
            self.procs.append(subprocess.Popen(cmd, start_new_session=True, env=env))
        typer.echo(f"swarmpath up: {self.n} local worker(s) started "
                   f"(pids {', '.join(str(p.pid) for p in self.procs)})", err=True)

    def stop(self, timeout: float = 20.0) -> None:
        for p in self.procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + timeout
        for p in self.procs:
            try:
                p.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(5)


def _host() -> str:
    from swarmpath.service.worker import default_worker_id

    return default_worker_id().rsplit("-", 1)[0]


def _local_login(data: Path, extra: Path | None) -> tuple[tuple[str, str], Path]:
    """A fresh random login for this start's local workers, written with the logins of
    ``extra`` (user:password lines) to DATA/zenoh-users.txt (0600)."""
    import secrets

    lines: list[str] = []
    if extra is not None:
        if not extra.is_file():
            raise InputError("--auth-dictionary", f"{str(extra)!r} does not exist")
        lines = [line.strip() for line in extra.read_text().splitlines() if line.strip()]
        bad = [line for line in lines if ":" not in line or line.startswith(":")]
        if bad:
            raise InputError("--auth-dictionary", f"{bad[0]!r} is not a user:password line")
    login = ("swarmpath-local", secrets.token_urlsafe(24))
    data.mkdir(parents=True, exist_ok=True)
    path = data / "zenoh-users.txt"
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w") as f:
        f.write("\n".join([f"{login[0]}:{login[1]}", *lines]) + "\n")
    os.chmod(path, 0o600)
    return login, path


@app.command()
def up(
    workers: Annotated[
        int, typer.Option("--workers", help="Local worker processes (0: one per CPU).",
                          show_default="CPU count")
    ] = 0,
    http: HttpOpt = DEFAULT_HTTP,
    zenoh: Annotated[str, typer.Option("--zenoh", help="Zenoh listen endpoint.")] = DEFAULT_ZENOH,
    data: DataOpt = Path(DEFAULT_DATA),
    slots: Annotated[int, typer.Option("--slots", help="Slots per local worker.")] = 1,
    prefix: PrefixOpt = "swarmpath",
    lease_seconds: LeaseOpt = 30.0,
    auth_dictionary: Annotated[
        Path | None,
        typer.Option("--auth-dictionary",
                     help="user:password lines of remote worker logins, admitted besides the "
                          "local workers' own random login."),
    ] = None,
    stacking: StackingOpt = True,
    log_level: LogOpt = "info",
) -> None:
    """Start the coordinator and N local workers; Ctrl-C (or SIGTERM) stops everything.

    The Zenoh router admits only logins: a random one made at each start for the local workers
    (in DATA/zenoh-users.txt, mode 0600), plus those of --auth-dictionary; every login may do
    only what a worker does (Zenoh access control)."""
    n = workers or os.cpu_count() or 1
    if not 0 <= workers <= 256:
        raise InputError("--workers", f"{workers} is not in [1, 256]")
    if not 1 <= slots <= 256:
        raise InputError("--slots", f"{slots} is not in [1, 256]")
    parse_http(http)
    # every option checked before anything is written into the data directory
    _coordinator_settings(data, [zenoh], prefix, lease_seconds, False, auth_dictionary, None)
    login, users = _local_login(data, auth_dictionary)
    settings = _coordinator_settings(data, [zenoh], prefix, lease_seconds, False, users, None)
    from swarmpath.service.zenoh_config import worker_access_control

    settings.zenoh_extra = {"access_control": worker_access_control(
        prefix, usernames=[line.split(":", 1)[0]
                           for line in users.read_text().splitlines() if ":" in line])}
    _logging(log_level)
    from swarmpath.service.coordinator import create_app

    local = LocalWorkers(n, _connectable(settings.zenoh_listen[0]), prefix, slots, log_level,
                         login, stacking)
    typer.echo(f"swarmpath up: http://{http}  zenoh {zenoh}  data {data}", err=True)
    _serve(create_app(settings, on_started=local.start, on_stopping=local.stop), http, log_level)


