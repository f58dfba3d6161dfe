#!/usr/bin/env python3
"""What a Zenoh router keeps in memory per connected client, and how it fills with traffic.

    .venv/bin/python scripts/bench/zenoh_memory.py [--clients 500] [--rounds 3]
        [--put-bytes 2000,60000] [--batch-size 65535,16384] [--answer-ms 0,2]
        [--query-bytes 200]

For each (batch size, put size, answer, query size): a router process (the coordinator's role:
a queryable and a subscriber, configured by swarmpath.service.zenoh_config.router_config with
``transport/link/tx/batch_size`` and ``transport/link/rx/buffer_size`` set to the batch size)
and one process holding ``--clients`` client sessions (the workers' role). Each round, every
client asks the queryable once (a query with a ``--query-bytes`` payload - 0: none, the
selector's parameters instead - and a 300-byte reply, like a lease request) and puts one
message of the put size (like a result frame). ``--answer-ms 0``: the router answers in
Zenoh's callback; N > 0: the callback queues the query and one thread answers the queries in
turn, N ms each (what the coordinator's bridge does: a lease costs it about 0.3 ms, longer
under load). Reported: the router's anonymous resident memory (MB, from /proc) alone, with the
clients connected, and after each round. Loopback only, free ports, scouting off; the
processes are stopped at the end. The growth is a high-water mark that depends on timing
(how many messages wait at once): repeat a row before reading much into one number.
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from farm_memory import proc_memory  # scripts/bench/farm_memory.py

ROOT = Path(__file__).resolve().parents[2]


def router(port: int, batch: int, answer_ms: float) -> None:
    """Serve until stdin closes; print the anonymous RSS for each line read."""
    import queue

    import zenoh

    from swarmpath.service.zenoh_config import router_config, to_zenoh

    extra = {"transport": {"link": {"tx": {"batch_size": batch}, "rx": {"buffer_size": batch}}}}
    session = zenoh.open(to_zenoh(router_config(f"tcp/127.0.0.1:{port}", extra=extra)))
    reply = b"r" * 300
    waiting: queue.SimpleQueue[object] = queue.SimpleQueue()

    def answer_in_turn() -> None:
        while True:
            query: object = waiting.get()
            time.sleep(answer_ms / 1000)
            query.reply(query.key_expr, reply)  # type: ignore[attr-defined]
            query.drop()  # type: ignore[attr-defined]

    if answer_ms > 0:
        threading.Thread(target=answer_in_turn, daemon=True).start()
        session.declare_queryable("probe/work", waiting.put)
    else:
        session.declare_queryable("probe/work", lambda q: q.reply(q.key_expr, reply))
    got = [0]
    session.declare_subscriber("probe/put/**", lambda _s: got.__setitem__(0, got[0] + 1))
    print("ready", flush=True)
    for line in sys.stdin:
        anon = proc_memory(os.getpid())[1]
        print(json.dumps({"at": line.strip(), "anon_mb": round(anon, 1), "puts": got[0]}),
              flush=True)
    os._exit(0)  # a session with callbacks can hang the interpreter's exit


def clients(port: int, count: int, rounds: int, put_bytes: int, query_bytes: int) -> None:
    """Open ``count`` sessions; one round of traffic per line read on stdin."""
    import zenoh

    from swarmpath.service.zenoh_config import client_config, to_zenoh

    conf = to_zenoh(client_config(f"tcp/127.0.0.1:{port}", timeout_ms=10000))
    sessions = [zenoh.open(conf) for _ in range(count)]
    payload = b"p" * put_bytes
    print("connected", flush=True)

    def ask(i: int) -> Any:
        if query_bytes:
            return sessions[i].get("probe/work", payload=b"q" * query_bytes, timeout=30.0)
        return sessions[i].get("probe/work?worker=w", timeout=30.0)

    def one(i: int) -> None:
        for _reply in ask(i):
            pass
        sessions[i].put(f"probe/put/{i}", payload,
                        congestion_control=zenoh.CongestionControl.BLOCK)

    for _ in range(rounds):
        sys.stdin.readline()
        threads = [threading.Thread(target=one, args=(i,)) for i in range(count)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        print("done", flush=True)
    sys.stdin.readline()
    os._exit(0)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def measure(count: int, rounds: int, put_bytes: int, batch: int, answer_ms: float,
            query_bytes: int) -> list[float]:
    """Router anonymous MB: alone, clients connected, after each round."""
    port = free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT / "services")}
    me = [sys.executable, __file__]
    procs: list[subprocess.Popen[str]] = []
    try:
        r = subprocess.Popen([*me, "--role", "router", "--port", str(port), "--batch-size",
                              str(batch), "--answer-ms", str(answer_ms)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
        procs.append(r)
        assert r.stdin is not None and r.stdout is not None
        r.stdout.readline()

        def ask(tag: str) -> float:
            assert r.stdin is not None and r.stdout is not None
            time.sleep(1.0)
            r.stdin.write(tag + "\n")
            r.stdin.flush()
            return float(json.loads(r.stdout.readline())["anon_mb"])

        out = [ask("alone")]
        c = subprocess.Popen([*me, "--role", "clients", "--port", str(port), "--clients",
                              str(count), "--rounds", str(rounds), "--put-bytes",
                              str(put_bytes), "--query-bytes", str(query_bytes)],
                             stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True, env=env)
        procs.append(c)
        assert c.stdin is not None and c.stdout is not None
        c.stdout.readline()
        out.append(ask("connected"))
        for i in range(rounds):
            c.stdin.write("\n")
            c.stdin.flush()
            c.stdout.readline()
            out.append(ask(f"round {i + 1}"))
        return out
    finally:
        for p in procs:
            p.kill()
            p.wait(10)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clients", type=int, default=500)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--put-bytes", default="2000,60000")
    ap.add_argument("--batch-size", default="65535,16384")
    ap.add_argument("--answer-ms", default="0,2")
    ap.add_argument("--query-bytes", default="200")
    ap.add_argument("--role", choices=["router", "clients"], help=argparse.SUPPRESS)
    ap.add_argument("--port", type=int, help=argparse.SUPPRESS)
    # (the roles' --batch-size and --answer-ms are single numbers)
    args = ap.parse_args(argv)
    if args.role == "router":
        router(args.port, int(args.batch_size), float(args.answer_ms))
        return 0
    if args.role == "clients":
        clients(args.port, args.clients, args.rounds, int(args.put_bytes),
                int(args.query_bytes))
        return 0
    try:
        puts = [int(x) for x in args.put_bytes.split(",")]
        batches = [int(x) for x in args.batch_size.split(",")]
        answers = [float(x) for x in args.answer_ms.split(",")]
        queries = [int(x) for x in args.query_bytes.split(",")]
    except ValueError:
        ap.error("--put-bytes, --batch-size, --answer-ms and --query-bytes are comma lists of "
                 "numbers")
    if args.clients < 1 or args.rounds < 1 or min(puts) < 1 or \
            not all(512 <= b <= 65535 for b in batches) or min(answers) < 0 or \
            min(queries) < 0:
        ap.error("--clients, --rounds, --put-bytes must be positive, --answer-ms and "
                 "--query-bytes not negative; --batch-size 512-65535")
    rounds = " | ".join(f"round {i + 1}" for i in range(args.rounds))
    print(f"| batch B | put B | answer ms | query B | alone | {args.clients} connected | "
          f"{rounds} | growth per client KB |")
    print("|" + "---:|" * (7 + args.rounds))
    for batch in batches:
        for put in puts:
            for answer in answers:
                for query in queries:
                    mb = measure(args.clients, args.rounds, put, batch, answer, query)
                    growth = (mb[-1] - mb[1]) * 1024 / args.clients
                    print(f"| {batch} | {put} | {answer:g} | {query} | "
                          + " | ".join(f"{x:.1f}" for x in mb) + f" | {growth:.0f} |",
                          flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
