#!/usr/bin/env python3
"""What each chunk compression setting would cost the recorder: the chunks of an uncompressed
recorder MCAP compressed with lz4 frame settings and zstd levels, and the CRC-32 of zlib and
ISA-L, in MB/s of one core (best of ``--rounds``, interleaved) with the compression ratio.

    SWARMPATH_MCAP_COMPRESSION=none PYTHONPATH=services .venv/bin/python \\
        scripts/bench/recorder_rebuild.py --runs 20000 --data /tmp/rec-bench
    .venv/bin/python scripts/bench/mcap_chunk_codecs.py /tmp/rec-bench/mcap/*.mcap

The chunks are the file's own (its records, 1 MiB each), so the text is the recorder's JSON.
"""

from __future__ import annotations

import argparse
import time
import zlib
from collections.abc import Callable
from pathlib import Path

import lz4.frame
import zstandard
from isal import isal_zlib
from mcap.reader import make_reader
from mcap.records import Chunk
from mcap.stream_reader import StreamReader


def chunks(path: Path, limit: int) -> list[bytes]:
    """The records of up to ``limit`` uncompressed chunks of the file at ``path``."""
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
        if summary is None or any(ci.compression for ci in summary.chunk_indexes):
            raise SystemExit(f"{path}: write it with SWARMPATH_MCAP_COMPRESSION=none")
        f.seek(0)
        out = [r.data for r in StreamReader(f, emit_chunks=True).records if isinstance(r, Chunk)]
    return out[:limit]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mcap", type=Path)
    ap.add_argument("--chunks", type=int, default=40)
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    data = chunks(args.mcap, args.chunks)
    size = sum(map(len, data))
    codecs: dict[str, Callable[[bytes], object]] = {
        "lz4 frame, level 0 (mcap's call, the default)": lz4.frame.compress,
        **{f"lz4 frame, level {lv} (fast acceleration)":
           (lambda b, lv=lv: lz4.frame.compress(b, compression_level=lv))
           for lv in (-1, -2, -4, -8, -16)},
        "lz4 frame, 4 MB blocks": lambda b: lz4.frame.compress(
            b, block_size=lz4.frame.BLOCKSIZE_MAX4MB),
        "lz4 frame, 64 KB blocks not linked": lambda b: lz4.frame.compress(
            b, block_linked=False),
        "zstd, level 3 (mcap's call)": zstandard.compress,
        **{f"zstd, level {lv}": zstandard.ZstdCompressor(level=lv).compress for lv in (1, -1, -5)},
        "crc32, zlib": zlib.crc32,
        "crc32, ISA-L": isal_zlib.crc32,
    }
    best = dict.fromkeys(codecs, float("inf"))
    ratio: dict[str, float] = {}
    for _ in range(args.rounds):
        for name, codec in codecs.items():
            start = time.process_time()
            out = [codec(b) for b in data]
            best[name] = min(best[name], time.process_time() - start)
            if isinstance(out[0], bytes):
                ratio[name] = size / sum(len(o) for o in out if isinstance(o, bytes))
    print(f"{len(data)} chunks, {size / 1e6:.1f} MB\n")
    print("| setting | MB/s of one core | ratio |\n| --- | ---: | ---: |")
    for name in codecs:
        r = f"{ratio[name]:.2f}" if name in ratio else "-"
        print(f"| {name} | {size / best[name] / 1e6:,.0f} | {r} |")


if __name__ == "__main__":
    main()
