// Reads an MCAP file with @mcap/core, the library Foxglove's own reader is built on, and prints
// what it saw as one JSON document. Exit code 1 (message on stderr) when the library rejects the
// file or when its indexes, statistics and streamed contents disagree.
//
// usage: node check.mjs FILE.mcap
import { open, readFile } from "node:fs/promises";

import { crc32 } from "@foxglove/crc";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";

function fail(message) {
  process.stderr.write(`mcap check: ${message}\n`);
  process.exit(1);
}

function countInto(counts, key) {
  counts[key] = (counts[key] ?? 0) + 1;
}

async function indexedPass(path, decompressHandlers) {
  const handle = await open(path, "r");
  try {
    const readable = {
      size: async () => BigInt((await handle.stat()).size),
      read: async (offset, length) => {
        const buffer = new Uint8Array(Number(length));
        const { bytesRead } = await handle.read(buffer, 0, buffer.length, Number(offset));
        if (bytesRead !== buffer.length) throw new Error(`short read at ${offset}`);
        return buffer;
      },
    };
    const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    const counts = {};
    for await (const message of reader.readMessages({ validateCrcs: true })) {
      countInto(counts, String(message.channelId));
    }
    return { reader, counts };
  } finally {
    await handle.close();
  }
}

function streamPass(bytes, decompressHandlers) {
  const stream = new McapStreamReader({ validateCrcs: true, decompressHandlers });
  stream.append(bytes);
  const counts = {};
  const metadata = {};
  let dataEnd;
  for (let record; (record = stream.nextRecord()); ) {
    if (record.type === "Message") countInto(counts, String(record.channelId));
    else if (record.type === "Metadata") metadata[record.name] = Object.fromEntries(record.metadata);
    else if (record.type === "DataEnd") dataEnd = record;
  }
  if (!stream.done()) fail("the stream reader did not reach the end of the file");
  return { counts, metadata, dataEnd };
}

const path = process.argv[2];
if (!path) fail("usage: node check.mjs FILE.mcap");
const decompressHandlers = await loadDecompressHandlers();
const bytes = new Uint8Array(await readFile(path));

let indexed;
try {
  indexed = await indexedPass(path, decompressHandlers);
} catch (error) {
  fail(`indexed reader: ${error.message}`);
}
let streamed;
try {
  streamed = streamPass(bytes, decompressHandlers);
} catch (error) {
  fail(`stream reader: ${error.message}`);
}

const { reader } = indexed;
const statistics = reader.statistics;
if (!statistics) fail("no Statistics record in the summary");
const statisticsCounts = Object.fromEntries(
  [...statistics.channelMessageCounts].map(([id, n]) => [String(id), Number(n)]),
);
const total = (counts) => Object.values(counts).reduce((a, b) => a + b, 0);
const same = (a, b) =>
  Object.keys({ ...a, ...b }).every((key) => (a[key] ?? 0) === (b[key] ?? 0));
if (!same(indexed.counts, streamed.counts)) fail("indexed and streamed message counts differ");
if (!same(indexed.counts, statisticsCounts)) fail("Statistics disagree with the messages read");
if (Number(statistics.messageCount) !== total(indexed.counts)) {
  fail("Statistics.messageCount disagrees with the messages read");
}
if (statistics.chunkCount !== reader.chunkIndexes.length) {
  fail("Statistics.chunkCount disagrees with the chunk indexes");
}
const withoutMessageIndexes = reader.chunkIndexes.filter((c) => c.messageIndexOffsets.size === 0);
if (withoutMessageIndexes.length > 0) fail("chunk indexes without message indexes");

// The data section CRC (DataEnd) covers every byte before the DataEnd record; 0 means "not set".
let dataSectionCrc = "absent";
if (streamed.dataEnd && streamed.dataEnd.dataSectionCrc !== 0) {
  const crc = crc32(bytes.subarray(0, Number(reader.dataEndOffset)));
  if (crc !== streamed.dataEnd.dataSectionCrc) fail("data section CRC mismatch");
  dataSectionCrc = "valid";
}

const channels = [...reader.channelsById.values()].map((channel) => {
  const schema = reader.schemasById.get(channel.schemaId);
  return {
    id: channel.id,
    topic: channel.topic,
    messageEncoding: channel.messageEncoding,
    schemaName: schema?.name ?? null,
    schemaEncoding: schema?.encoding ?? null,
    schema: schema ? JSON.parse(new TextDecoder().decode(schema.data)) : null,
    messages: indexed.counts[String(channel.id)] ?? 0,
  };
});

process.stdout.write(
  JSON.stringify({
    library: reader.header.library,
    profile: reader.header.profile,
    chunks: reader.chunkIndexes.length,
    compression: [...new Set(reader.chunkIndexes.map((c) => c.compression))],
    messageCount: Number(statistics.messageCount),
    dataSectionCrc,
    metadata: streamed.metadata,
    metadataIndexes: reader.metadataIndexes.map((m) => m.name),
    channels,
  }),
);
