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
from swarmpath.service.identity import read_logins

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


def _allowed_hosts(http: str, names: list[str] | None) -> list[str]:
    from swarmpath.service.http.middleware import allowed_hosts

    env = [n.strip() for n in os.environ.get("SWARMPATH_ALLOWED_HOSTS", "").split(",")]
    return allowed_hosts(parse_http(http)[0], [n for n in [*(names or []), *env] if n])


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
WarmOpt = Annotated[
    bool, typer.Option("--warm/--no-warm", envvar="SWARMPATH_WARM",
                       help="Slots compile (or load from numba's cache) the compiled kernels "
                            "before they take work, so no lease waits for the compiler (the "
                            "first start of a tree: 2-3 min of CPU, shared by the slots; "
                            "SWARMPATH_WARM=0 is --no-warm).")
]
AllowedHostOpt = Annotated[
    list[str] | None,
    typer.Option("--allowed-host", metavar="NAME",
                 help="A Host name the HTTP side answers besides loopback's and the --http "
                      "address (repeat; also SWARMPATH_ALLOWED_HOSTS, comma-separated; '*': "
                      "any). Other Host headers get a 400 (DNS rebinding).")
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
                     help="Zenoh user/password file (user:password lines): workers must log in. "
                          "Without it (and without mutual TLS) a login is made in "
                          "DATA/zenoh-users.txt."),
    ] = None,
    insecure: Annotated[
        bool, typer.Option("--insecure",
                           help="No Zenoh login: any process reaching the router can lease "
                                "work and report results.")
    ] = False,
    shm: ShmOpt = False,
    zenoh_config: ZConfOpt = None,
    allowed_host: AllowedHostOpt = None,
    log_level: LogOpt = "info",
) -> None:
    """Run the coordinator: REST API, job queue and the Zenoh router (no local workers).

    Workers log in: with --auth-dictionary, or else with the login made in DATA/zenoh-users.txt
    (start them with --login-file DATA/zenoh-users.txt); every login may do only what a worker
    does (Zenoh access control). --insecure turns logins off."""
    from swarmpath.cli.logins import mutual_tls, standalone_login, with_access_control

    parse_http(http)
    if insecure and auth_dictionary is not None:
        raise InputError("--insecure", "--auth-dictionary makes workers log in: choose one")
    settings = _coordinator_settings(data, zenoh, prefix, lease_seconds, shm, auth_dictionary,
                                     zenoh_config)
    settings.allowed_hosts = _allowed_hosts(http, allowed_host)
    _logging(log_level)
    if insecure:
        warning = ("INSECURE (--insecure): no Zenoh login; any process that reaches "
                   f"{', '.join(settings.zenoh_listen)} can lease work and report results")
        typer.echo(f"swarmpath coordinator: WARNING: {warning}", err=True)
        logging.getLogger("swarmpath.coordinator").warning("%s", warning)
    elif auth_dictionary is None and not mutual_tls(settings.zenoh_extra):
        users = standalone_login(data)
        settings.dictionary_file = str(users)
        typer.echo(f"swarmpath coordinator: workers log in with {users} (0600): swarmpath "
                   f"worker --connect {_connectable(settings.zenoh_listen[0])} --login-file "
                   f"{users}", err=True)
    if settings.dictionary_file is not None:
        names = list(read_logins(settings.dictionary_file))
        settings.zenoh_extra = with_access_control(prefix, names, settings.zenoh_extra)
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
    login_file: Annotated[
        Path | None,
        typer.Option("--login-file", envvar="SWARMPATH_ZENOH_LOGIN_FILE",
                     help="user:password file (its first line), e.g. the coordinator's "
                          "DATA/zenoh-users.txt; instead of --user/--password."),
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
    warm: WarmOpt = True,
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
    if login_file is not None:
        from swarmpath.cli.logins import login_file as read_login_file

        if user or password:
            raise InputError("--login-file", "gives the user and password: drop --user/--password")
        user, password = read_login_file(login_file)
    if bool(user) != bool(password):
        raise InputError("--password" if user else "--user", "user and password go together")
    if user:
        from swarmpath.service.identity import id_for
        from swarmpath.service.worker import default_worker_id

        try:
            worker_id = id_for(user, worker_id, default_worker_id())
            keys.worker_token(worker_id)
        except ValueError as exc:
            raise InputError("--id", str(exc)) from None
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
        stacking=stacking, warm=warm,
    )
    _logging(log_level)
    raise typer.Exit(run_worker(settings))


class LocalWorkers:
    """The worker subprocesses of ``swarmpath up`` (fork+exec'd, so nothing of Zenoh is shared)."""

    def __init__(self, logins: list[tuple[str, str]], connect: str, prefix: str, slots: int,
                 log_level: str, stacking: bool = True, warm: bool = True):
        self.n, self.connect, self.prefix, self.slots = len(logins), connect, prefix, slots
        self.stacking, self.warm = stacking, warm
        self.log_level = log_level
        # one login per worker, named by its id: (user, password), handed over in the
        # environment, never in argv
        self.logins = logins
        self.procs: list[subprocess.Popen[bytes]] = []

    @staticmethod
    def ids(n: int) -> list[str]:
        return [f"{_host()}-{os.getpid()}-w{i}" for i in range(n)]

    def start(self) -> None:
        for worker_id, password in self.logins:
            cmd = [
                sys.executable, "-m", "swarmpath.cli", "worker", "--connect", self.connect,
                "--prefix", self.prefix, "--slots", str(self.slots),
                "--exit-with-parent", str(os.getpid()), "--log-level", self.log_level,
                "--id", worker_id, *([] if self.stacking else ["--no-stacking"]),
                *([] if self.warm else ["--no-warm"]),
            ]
            env = dict(os.environ)
            env.pop("SWARMPATH_ZENOH_LOGIN_FILE", None)
            env["SWARMPATH_ZENOH_USER"], env["SWARMPATH_ZENOH_PASSWORD"] = worker_id, password
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
    warm: WarmOpt = True,
    allowed_host: AllowedHostOpt = None,
    log_level: LogOpt = "info",
) -> None:
    """Start the coordinator and N local workers; Ctrl-C (or SIGTERM) stops everything.

    The Zenoh router admits only logins: a random one per local worker made at each start and
    named by its id (in DATA/zenoh-users.txt, mode 0600), plus those of --auth-dictionary; every
    login may do only what a worker does (Zenoh access control), and a worker id belongs to its
    login (lease requests prove it)."""
    n = workers or os.cpu_count() or 1
    if not 0 <= workers <= 256:
        raise InputError("--workers", f"{workers} is not in [1, 256]")
    if not 1 <= slots <= 256:
        raise InputError("--slots", f"{slots} is not in [1, 256]")
    parse_http(http)
    # every option checked before anything is written into the data directory
    _coordinator_settings(data, [zenoh], prefix, lease_seconds, False, auth_dictionary, None)
    from swarmpath.cli.logins import local_logins, with_access_control

    logins, users = local_logins(data, LocalWorkers.ids(n), auth_dictionary)
    settings = _coordinator_settings(data, [zenoh], prefix, lease_seconds, False, users, None)
    settings.zenoh_extra = with_access_control(prefix, list(read_logins(users)), None)
    settings.allowed_hosts = _allowed_hosts(http, allowed_host)
    _logging(log_level)
    from swarmpath.service.coordinator import create_app

    local = LocalWorkers(logins, _connectable(settings.zenoh_listen[0]), prefix, slots,
                         log_level, stacking, warm)
    typer.echo(f"swarmpath up: http://{http}  zenoh {zenoh}  data {data}", err=True)
    _serve(create_app(settings, on_started=local.start, on_stopping=local.stop), http, log_level)


