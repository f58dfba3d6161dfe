"""The mcap ``Writer`` with a cheaper message path and chunk finalization, same bytes.

The recorder writes two messages per benchmark run, tens of thousands of runs per second; the
mcap package spends Python per message (a record object, five ``struct`` packs and a seek, one
pack per time and offset of the message index) and checksums with zlib's CRC-32 (about 3 GB/s
here, several microseconds per run). :class:`FastWriter` is a ``Writer`` whose

* :meth:`FastWriter.add_parts` appends a message record with one ``struct`` pack for its head
  (its data may come in parts, written one after the other), with the statistics, message index
  entry and chunk cut of ``Writer.add_message``. The records are kept as a list of byte strings
  and joined once when the chunk is cut, instead of being copied into the chunk's growing
  ``BytesIO`` (which reallocates, and so copies, as it grows); they go into that buffer first
  only when mcap writes a record of its own into the chunk (a schema or channel registered
  while the chunk is open), so the records keep their order;
* chunk finalization and buffer flushing (the ``Writer``'s private ``__finalize_chunk`` and
  ``__flush``, overridden) compute the chunk and data-section CRCs with ISA-L's CRC-32 (the same
  polynomial, the same values, an order of magnitude faster: :mod:`isal.isal_zlib`), write the
  chunk record's head and its compressed records straight to the file instead of copying them
  through a record buffer, and write message indexes in two packs each (:class:`PackedIndex`).

The chunk compression calls are mcap's own (``lz4.frame.compress(data)``,
``zstandard.compress(data)``), so a file is byte for byte the one ``Writer`` writes (a test
writes the same job both ways). This reaches into the writer's private state, so
:func:`writer_class` returns it only for the mcap versions it was checked against (``VERIFIED``)
and when those attributes are there; otherwise the plain ``Writer``.
"""

from __future__ import annotations

import struct
from itertools import chain
from typing import Any

import lz4.frame
import zstandard
from isal.isal_zlib import crc32
from mcap.opcode import Opcode
from mcap.records import ChunkIndex, MessageIndex
from mcap.writer import CompressionType, IndexType, Writer
from mcap.writer import __version__ as MCAP_VERSION

VERIFIED = ("1.6.",)  # mcap versions whose writer internals this was checked against
_MESSAGE_HEAD = struct.Struct("<BQHIQQ")  # opcode, record length, channel, sequence, 2 times
_MESSAGE = int(Opcode.MESSAGE)  # (an enum member's look-up costs more than a global's)
_MESSAGE_FIXED = 2 + 4 + 8 + 8  # a message record's fields before its data
_INDEX_HEAD = struct.Struct("<BQHI")  # opcode, record length, channel, entries' byte length
# a chunk record up to its compression name: opcode, record length, start and end time,
# uncompressed size, uncompressed CRC, name length
_CHUNK_HEAD = struct.Struct("<BQQQQII")
_CHUNK_FIXED = 8 + 8 + 8 + 4 + 4 + 8  # the chunk record's fields besides name and records
_U64 = struct.Struct("<Q")
_COMPRESSION_NAMES = {CompressionType.LZ4: "lz4", CompressionType.ZSTD: "zstd",
                      CompressionType.NONE: ""}
# what FastWriter uses of Writer: methods it overrides or calls, attributes set by __init__
_METHODS = ("_Writer__flush", "_Writer__finalize_chunk", "_Writer__maybe_finalize_chunk")
_STATE = ("_Writer__chunk_builder", "_Writer__statistics", "_Writer__chunk_size",
          "_Writer__stream", "_Writer__record_builder", "_Writer__compression",
          "_Writer__enable_crcs", "_Writer__enable_data_crcs", "_Writer__data_section_crc",
          "_Writer__chunk_indices", "_Writer__index_types")


class PackedIndex(MessageIndex):
    """A chunk's message index for one channel, written in two ``struct`` packs (the same bytes
    as ``MessageIndex.write``, which packs each time and offset on its own)."""

    def write(self, stream: Any) -> None:
        n = len(self.records)
        stream.write(_INDEX_HEAD.pack(Opcode.MESSAGE_INDEX, 2 + 4 + 16 * n, self.channel_id,
                                      16 * n))
        stream.write(struct.pack(f"<{2 * n}Q", *chain.from_iterable(self.records)))


def writer_class() -> type[Writer]:
    """:class:`FastWriter` where this mcap version was checked, else ``Writer``."""
    if MCAP_VERSION.startswith(VERIFIED) and all(hasattr(Writer, m) for m in _METHODS):
        return FastWriter
    return Writer


class FastWriter(Writer):
    """See the module docstring. Construct it through :func:`writer_class`; after
    construction, :attr:`checked` is False when the writer's private state is not what this
    was written against (then use a plain ``Writer``)."""

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        chunk = getattr(self, "_Writer__chunk_builder", None)
        self.checked = (all(hasattr(self, name) for name in _STATE) and chunk is not None
                        and hasattr(getattr(chunk, "record_writer", None), "_buffer")
                        and hasattr(chunk, "message_indices")
                        and hasattr(self._Writer__statistics, "channel_message_counts"))
        self._pending: list[bytes] = []  # message records of the open chunk, not in its buffer
        self._pending_size = 0

    def _spill(self) -> None:
        """The pending message records into the chunk's buffer (before a record of mcap's)."""
        if self._pending:
            self._Writer__chunk_builder.record_writer._buffer.write(b"".join(self._pending))
            self._pending.clear()
            self._pending_size = 0

    def register_schema(self, *args: Any, **kwargs: Any) -> int:
        self._spill()
        return super().register_schema(*args, **kwargs)

    def register_channel(self, *args: Any, **kwargs: Any) -> int:
        self._spill()
        return super().register_channel(*args, **kwargs)

    def add_message(self, *args: Any, **kwargs: Any) -> None:
        self._spill()
        super().add_message(*args, **kwargs)

    # -------------------------------------------------------------------------------- messages
    def add_parts(self, channel_id: int, log_ns: int, parts: tuple[bytes, ...]) -> None:
        """``add_message(channel_id, log_time=log_ns, publish_time=log_ns, data=b"".join(parts))``
        with sequence 0, in fewer Python steps."""
        stats, chunk = self._Writer__statistics, self._Writer__chunk_builder
        if not stats.message_count or log_ns < stats.message_start_time:
            stats.message_start_time = log_ns
        if log_ns > stats.message_end_time:
            stats.message_end_time = log_ns
        stats.channel_message_counts[channel_id] += 1
        stats.message_count += 1
        if not chunk.num_messages or log_ns < chunk.message_start_time:
            chunk.message_start_time = log_ns
        if log_ns > chunk.message_end_time:
            chunk.message_end_time = log_ns
        offset = chunk.record_writer._buffer.tell() + self._pending_size  # in the chunk
        index = chunk.message_indices.get(channel_id)
        if not index:
            index = chunk.message_indices[channel_id] = PackedIndex(
                channel_id=channel_id, records=[])
        index.records.append((log_ns, offset))
        chunk.num_messages += 1
        size = len(parts[0]) if len(parts) == 1 else sum(map(len, parts))
        pending = self._pending
        pending.append(_MESSAGE_HEAD.pack(_MESSAGE, _MESSAGE_FIXED + size, channel_id, 0,
                                          log_ns, log_ns))
        pending += parts
        self._pending_size += 9 + _MESSAGE_FIXED + size
        if offset + 9 + _MESSAGE_FIXED + size > self._Writer__chunk_size:
            self._Writer__finalize_chunk()

    # ---------------------------------------------------------------- Writer's private steps
    def _put_data(self, data: Any) -> None:
        """Write ``data`` to the file as part of the data section (its CRC follows it)."""
        if self._Writer__enable_data_crcs:
            self._Writer__data_section_crc = crc32(data, self._Writer__data_section_crc)
        self._Writer__stream.write(data)

    def _Writer__flush(self) -> None:  # overrides Writer.__flush
        self._put_data(self._Writer__record_builder.end())

    def _Writer__finalize_chunk(self) -> None:  # overrides Writer.__finalize_chunk
        chunk = self._Writer__chunk_builder
        if not chunk or chunk.num_messages == 0:
            return  # (records other than messages wait for the next chunk, as in Writer)
        self._Writer__statistics.chunk_count += 1
        if chunk.record_writer._buffer.tell():  # records of mcap's first, then the messages
            self._spill()
            records = chunk.end()
        else:
            records = b"".join(self._pending)
            self._pending.clear()
            self._pending_size = 0
        compression = self._Writer__compression
        if compression == CompressionType.LZ4:
            data = lz4.frame.compress(records)
        elif compression == CompressionType.ZSTD:
            data = zstandard.compress(records)
        else:
            data = records
        name = _COMPRESSION_NAMES[compression].encode()
        self._Writer__flush()  # what is buffered before the chunk
        start = self._Writer__stream.tell()
        length = _CHUNK_FIXED + len(name) + len(data)
        self._put_data(_CHUNK_HEAD.pack(
            Opcode.CHUNK, length, chunk.message_start_time, chunk.message_end_time,
            len(records), crc32(records) if self._Writer__enable_crcs else 0, len(name))
            + name + _U64.pack(len(data)))
        self._put_data(data)
        index = ChunkIndex(
            message_start_time=chunk.message_start_time,
            message_end_time=chunk.message_end_time,
            chunk_start_offset=start,
            chunk_length=9 + length,
            message_index_offsets={},
            message_index_length=0,
            compression=name.decode(),
            compressed_size=len(data),
            uncompressed_size=len(records),
        )
        if self._Writer__index_types & IndexType.MESSAGE:
            first = start + 9 + length  # the message indexes follow the chunk
            out = self._Writer__record_builder
            for channel_id, entries in chunk.message_indices.items():
                index.message_index_offsets[channel_id] = first + out.count
                entries.write(out)
            index.message_index_length = out.count
        self._Writer__flush()
        self._Writer__chunk_indices.append(index)
        chunk.reset()
