#!/usr/bin/env node
// Reads an MCAP file with a reader that is not ovton's, as Foxglove does: Foxglove's @mcap/core (indexed reader, every
// chunk's CRC checked) and its ROS 2 CDR decoder, driven by the message definitions the file carries. Prints one JSON
// object: the profile, and per topic the schema name and encoding, the message count and the first message decoded
// (byte arrays shown by their length); the data section's CRC (magic to Data End, as @mcap/core's writer counts it) is
// recomputed when the file gives one. Exits 1 when the file cannot be read this way (no index, a schema its parser
// refuses, a message its decoder cannot read, trailing bytes after a message).
//
//   node check_mcap.mjs FILE.mcap
import fs from "node:fs";
import { McapIndexedReader } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "@foxglove/wasm-lz4";
import { crc32 } from "@foxglove/crc";
import { FileReadable } from "./file_readable.mjs";

function brief(v) {
  if (v instanceof Uint8Array || (ArrayBuffer.isView(v) && v.length > 16)) return `<${v.length} values>`;
  if (Array.isArray(v)) return v.length > 16 ? `<${v.length} items>` : v.map(brief);
  if (typeof v === "bigint") return v.toString();
  if (v && typeof v === "object") return Object.fromEntries(Object.entries(v).map(([k, x]) => [k, brief(x)]));
  return v;
}

async function main() {
  const file = process.argv[2];
  if (!file) throw new Error("usage: check_mcap.mjs FILE.mcap");
  await zstd.isLoaded;
  await lz4.isLoaded;
  const reader = await McapIndexedReader.Initialize({
    readable: new FileReadable(file),
    decompressHandlers: {
      zstd: (data, size) => zstd.decompress(data, Number(size)),
      lz4: (data, size) => lz4(data, Number(size)),
    },
  });
  const topics = {};
  const decoders = new Map();
  for (const [id, ch] of reader.channelsById) {
    const schema = reader.schemasById.get(ch.schemaId);
    const name = schema ? schema.name : "";
    topics[ch.topic] = { schema: name, schemaEncoding: schema?.encoding, messageEncoding: ch.messageEncoding, count: 0 };
    if (schema && schema.encoding === "ros2msg" && ch.messageEncoding === "cdr")
      decoders.set(id, new MessageReader(parse(new TextDecoder().decode(schema.data), { ros2: true })));
  }
  for await (const m of reader.readMessages({ validateCrcs: true })) {
    const ch = reader.channelsById.get(m.channelId);
    const t = topics[ch.topic];
    const dec = decoders.get(m.channelId);
    if (!dec) throw new Error(`${ch.topic}: no ROS 2 schema to decode with`);
    const msg = dec.readMessage(m.data);
    if (dec.lastReadHadTrailingBytes()) throw new Error(`${ch.topic}: message ${t.count} has trailing bytes`);
    if (t.count++ === 0) t.first = brief(msg);
  }
  let dataCrc = "absent";
  if (reader.dataSectionCrc !== undefined) {
    const bytes = fs.readFileSync(file).subarray(0, Number(reader.dataEndOffset));
    if (crc32(bytes) !== reader.dataSectionCrc)
      throw new Error(`data section CRC ${crc32(bytes)} differs from the file's ${reader.dataSectionCrc}`);
    dataCrc = "ok";
  }
  const stats = reader.statistics;
  console.log(
    JSON.stringify({
      profile: reader.header.profile,
      library: reader.header.library,
      messages: stats ? Number(stats.messageCount) : undefined,
      chunks: reader.chunkIndexes.length,
      dataCrc,
      topics,
    }),
  );
}

main().catch((e) => {
  console.error(`check_mcap: ${e.message}`);
  process.exit(1);
});
