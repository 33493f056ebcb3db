// SPDX-License-Identifier: BSD-3-Clause
// Reads an MCAP file with @mcap/core's stream and indexed readers, decodes and re-encodes every
// message with @foxglove/rosmsg2-serialization, and prints one JSON report (exit 1 on any error).

import { createHash } from "node:crypto";
import fs from "node:fs/promises";

import { crc32Final, crc32Init, crc32Update } from "@foxglove/crc";
import { parse as parseMsgDefinition } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";

import { kDecompressHandlers, loadCompression } from "./compression.mjs";

const kUsage = "usage: node read_mcap.mjs FILE.mcap";
const kReadSize = 1 << 20;
const kSummaryHead = 8; // array elements shown in "head"
const kMagic = Buffer.from([0x89, 0x4d, 0x43, 0x41, 0x50, 0x30, 0x0d, 0x0a]); // "\x89MCAP0\r\n"
const kOpDataEnd = 0x0f;

/** Collects errors once per distinct text, with a count, so a bad file gives a short report. */
class Errors {
  static kMaxListed = 50;
  #counts = new Map();
  add(text) {
    this.#counts.set(text, (this.#counts.get(text) ?? 0) + 1);
  }
  list() {
    const all = [...this.#counts].map(([text, n]) => (n > 1 ? `${text} (x${n})` : text));
    if (all.length <= Errors.kMaxListed) {
      return all;
    }
    const more = all.length - Errors.kMaxListed;
    return [...all.slice(0, Errors.kMaxListed), `... and ${more} more errors`];
  }
}

/** IReadable over a FileHandle, for McapIndexedReader. */
function fileReadable(handle, size) {
  return {
    size: async () => BigInt(size),
    async read(offset, length) {
      const buffer = new Uint8Array(Number(length));
      for (let done = 0; done < buffer.byteLength; ) {
        const position = Number(offset) + done;
        const { bytesRead } = await handle.read(buffer, done, buffer.byteLength - done, position);
        if (bytesRead === 0) {
          throw new Error(`read past the end of the file at ${position}`);
        }
        done += bytesRead;
      }
      return buffer;
    },
  };
}

/** The message as JSON: bigints as numbers, typed and long arrays as {length, head}. */
function toJson(value) {
  if (typeof value === "bigint") {
    return Number(value);
  }
  if (ArrayBuffer.isView(value)) {
    return { length: value.length, head: Array.from(value.slice(0, kSummaryHead), toJson) };
  }
  if (Array.isArray(value)) {
    const items = value.length > kSummaryHead ? value.slice(0, kSummaryHead) : value;
    const json = items.map(toJson);
    return value.length > kSummaryHead ? { length: value.length, head: json } : json;
  }
  if (typeof value === "number" && !Number.isFinite(value)) {
    return String(value); // JSON has no NaN or Infinity
  }
  if (value !== null && typeof value === "object") {
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, toJson(v)]));
  }
  return value;
}

function hasNonAsciiString(value) {
  if (typeof value === "string") {
    return !/^[\x00-\x7f]*$/.test(value);
  }
  if (value !== null && typeof value === "object" && !ArrayBuffer.isView(value)) {
    return Object.values(value).some(hasNonAsciiString);
  }
  return false;
}

function messageKey(message) {
  const digest = createHash("sha1").update(message.data).digest("hex");
  const { channelId, logTime, publishTime, sequence } = message;
  return `${channelId}/${logTime}/${publishTime}/${sequence}/${digest}`;
}

function sameBytes(a, b) {
  return a.byteLength === b.byteLength && Buffer.compare(a, b) === 0;
}

function sameChannel(a, b) {
  return (
    a.id === b.id &&
    a.schemaId === b.schemaId &&
    a.topic === b.topic &&
    a.messageEncoding === b.messageEncoding &&
    JSON.stringify([...a.metadata].sort()) === JSON.stringify([...b.metadata].sort())
  );
}

function sameSchema(a, b) {
  return (
    a.id === b.id && a.name === b.name && a.encoding === b.encoding && sameBytes(a.data, b.data)
  );
}

/** Decodes and re-encodes messages of one schema; null when the schema cannot be used. */
class Codec {
  constructor(schema, errors) {
    this.reader = null;
    if (schema === undefined) {
      return;
    }
    if (schema.encoding !== "ros2msg") {
      errors.add(
        `schema ${schema.id} (${schema.name}): encoding "${schema.encoding}" is not ros2msg`,
      );
      return;
    }
    try {
      const text = new TextDecoder("utf-8", { fatal: true }).decode(schema.data);
      const definitions = parseMsgDefinition(text, { ros2: true });
      this.reader = new MessageReader(definitions);
      this.writer = new MessageWriter(definitions);
    } catch (error) {
      errors.add(
        `schema ${schema.id} (${schema.name}) does not parse as ros2msg: ${error.message}`,
      );
      this.reader = null;
    }
  }
}

/** Per-channel results of the stream pass. */
class TopicReport {
  constructor(channel, schema) {
    this.channel = channel;
    this.schema = schema;
    this.count = 0;
    this.reencodedIdentical = 0;
    this.reencodedPadded = 0;
    this.reencodeSkipped = 0;
    this.first = undefined;
    this.last = undefined;
    this.firstLogTime = undefined;
    this.lastLogTime = undefined;
  }

  toJson() {
    const json = {
      topic: this.channel.topic,
      type: this.schema?.name ?? null,
      schema_encoding: this.schema?.encoding ?? null,
      message_encoding: this.channel.messageEncoding,
      count: this.count,
      reencoded_identical: this.reencodedIdentical,
    };
    if (this.reencodedPadded > 0) {
      json.reencoded_identical_but_end_padding = this.reencodedPadded;
    }
    if (this.reencodeSkipped > 0) {
      json.reencode_skipped_non_ascii = this.reencodeSkipped;
    }
    // Exact decimal strings: log times pass 2^53.
    json.first_log_time_ns = this.firstLogTime === undefined ? null : String(this.firstLogTime);
    json.last_log_time_ns = this.lastLogTime === undefined ? null : String(this.lastLogTime);
    json.first = this.first === undefined ? null : toJson(this.first);
    json.last = this.last === undefined ? null : toJson(this.last);
    return json;
  }
}

/**
 * Checks one message's CDR: decode, no stray trailing bytes, and re-encoding gives the same bytes.
 * XCDR end padding (up to 3 zero bytes announced in the encapsulation options' low 2 bits), which
 * @foxglove/cdr does not write, is counted apart rather than as a mismatch.
 */
function checkMessage(report, codec, message, errors) {
  const where = `${report.channel.topic}: message at log time ${message.logTime}`;
  let decoded;
  try {
    decoded = codec.reader.readMessage(message.data);
  } catch (error) {
    errors.add(`${report.channel.topic}: a message does not decode: ${error.message}`);
    return undefined;
  }
  const data = message.data;
  const used = codec.reader.lastReadByteLength();
  const tail = data.subarray(used);
  const announcedPadding = data.length >= 4 ? data[3] & 3 : 0;
  if (tail.length > 0 && (tail.length !== announcedPadding || tail.some((b) => b !== 0))) {
    errors.add(
      `${where}: ${tail.length} bytes after the message (padding announced: ${announcedPadding})`,
    );
  }
  if (hasNonAsciiString(decoded)) {
    // NOTE(harness): @foxglove/cdr writes strings by UTF-16 length; it cannot re-encode these.
    report.reencodeSkipped += 1;
    return decoded;
  }
  let reencoded;
  try {
    reencoded = codec.writer.writeMessage(decoded);
  } catch (error) {
    errors.add(`${report.channel.topic}: a message does not re-encode: ${error.message}`);
    return decoded;
  }
  if (sameBytes(reencoded, data)) {
    report.reencodedIdentical += 1;
  } else if (
    tail.length > 0 &&
    reencoded.length === used &&
    sameBytes(reencoded.subarray(0, 2), data.subarray(0, 2)) &&
    reencoded[2] === data[2] &&
    (reencoded[3] & ~3) === (data[3] & ~3) &&
    sameBytes(reencoded.subarray(4), data.subarray(4, used))
  ) {
    report.reencodedPadded += 1;
  } else {
    let at = 0;
    while (at < Math.min(reencoded.length, data.length) && reencoded[at] === data[at]) {
      ++at;
    }
    errors.add(
      `${where}: re-encoded bytes differ (${data.length} bytes in the file, ${reencoded.length} ` +
        `re-encoded, first difference at byte ${at})`,
    );
  }
  return decoded;
}

function newStreamState() {
  return {
    header: undefined,
    schemas: new Map(),
    channels: new Map(),
    summaryOnlyChannels: [],
    topics: new Map(),
    codecs: new Map(),
    messageKeys: new Map(),
    messageCount: 0,
    chunkCount: 0,
    compressions: new Set(),
    metadataNames: [],
    attachmentCount: 0,
    minLogTime: undefined,
    maxLogTime: undefined,
    complete: false,
  };
}

/** Reads the whole file through McapStreamReader (CRCs checked), filling `state` as it goes. */
async function streamPass(handle, state, errors) {
  const reader = new McapStreamReader({
    validateCrcs: true,
    includeChunks: true,
    decompressHandlers: kDecompressHandlers,
  });
  const buffer = new Uint8Array(kReadSize);
  for (let position = 0; ; ) {
    const { bytesRead } = await handle.read(buffer, 0, buffer.byteLength, position);
    if (bytesRead === 0) {
      break;
    }
    position += bytesRead;
    reader.append(buffer.subarray(0, bytesRead));
    for (let record; (record = reader.nextRecord()); ) {
      handleRecord(state, record, errors);
    }
  }
  if (!reader.done()) {
    errors.add(`stream reader: the file ends before its footer and closing magic`);
  }
  state.complete = true;
}

function handleRecord(state, record, errors) {
  switch (record.type) {
    case "Header":
      state.header = record;
      break;
    case "Schema": {
      const known = state.schemas.get(record.id);
      if (known !== undefined && !sameSchema(known, record)) {
        errors.add(`schema ${record.id} is written twice with different contents`);
      }
      state.schemas.set(record.id, record);
      break;
    }
    case "Channel":
      if (!state.channels.has(record.id)) {
        state.channels.set(record.id, record);
        if (record.schemaId !== 0 && !state.schemas.has(record.schemaId)) {
          errors.add(
            `channel ${record.id} (${record.topic}) refers to schema ${record.schemaId} before it`,
          );
        }
      }
      break;
    case "Message":
      handleMessage(state, record, errors);
      break;
    case "Chunk":
      state.chunkCount += 1;
      state.compressions.add(record.compression);
      break;
    case "Metadata":
      state.metadataNames.push(record.name);
      break;
    case "Attachment":
      state.attachmentCount += 1;
      break;
    default:
      break;
  }
}

function handleMessage(state, message, errors) {
  const channel = state.channels.get(message.channelId);
  let report = state.topics.get(message.channelId);
  if (report === undefined) {
    report = new TopicReport(channel, state.schemas.get(channel.schemaId));
    state.topics.set(message.channelId, report);
    if (channel.messageEncoding !== "cdr") {
      errors.add(`${channel.topic}: message encoding "${channel.messageEncoding}" is not cdr`);
    }
    if (channel.schemaId === 0) {
      errors.add(`${channel.topic}: channel has no schema`);
    }
  }
  report.count += 1;
  report.firstLogTime ??= message.logTime;
  report.lastLogTime = message.logTime;
  state.messageCount += 1;
  const key = messageKey(message);
  state.messageKeys.set(key, (state.messageKeys.get(key) ?? 0) + 1);
  const t = message.logTime;
  state.minLogTime = state.minLogTime === undefined || t < state.minLogTime ? t : state.minLogTime;
  state.maxLogTime = state.maxLogTime === undefined || t > state.maxLogTime ? t : state.maxLogTime;

  if (!state.codecs.has(channel.schemaId)) {
    state.codecs.set(channel.schemaId, new Codec(state.schemas.get(channel.schemaId), errors));
  }
  const codec = state.codecs.get(channel.schemaId);
  if (codec.reader === null || channel.messageEncoding !== "cdr") {
    return;
  }
  const decoded = checkMessage(report, codec, message, errors);
  if (decoded !== undefined) {
    report.first ??= decoded;
    report.last = decoded;
  }
}

/**
 * Walks the data section's record frames from the leading magic to DataEnd and checks its
 * data_section_crc (neither @mcap/core reader does); a zero CRC means "not written".
 */
async function checkDataSectionCrc(handle, size, errors) {
  const frame = Buffer.alloc(9);
  let offset = kMagic.length;
  for (;;) {
    if (offset + 9 > size) {
      errors.add("data section: no DataEnd record");
      return;
    }
    await handle.read(frame, 0, 9, offset);
    const length = frame.readBigUInt64LE(1);
    if (frame[0] === kOpDataEnd) {
      break;
    }
    offset += 9 + Number(length);
  }
  const stored = Buffer.alloc(4);
  await handle.read(stored, 0, 4, offset + 9);
  const expected = stored.readUInt32LE(0);
  if (expected === 0) {
    return;
  }
  let crc = crc32Init();
  const buffer = new Uint8Array(kReadSize);
  for (let position = 0; position < offset; ) {
    const want = Math.min(buffer.byteLength, offset - position);
    const { bytesRead } = await handle.read(buffer, 0, want, position);
    crc = crc32Update(crc, buffer.subarray(0, bytesRead));
    position += bytesRead;
  }
  const actual = crc32Final(crc);
  if (actual !== expected) {
    errors.add(`data section CRC ${actual} differs from DataEnd's ${expected}`);
  }
}

/** Compares the summary (through McapIndexedReader) with what the stream pass saw. */
async function indexedPass(indexed, stream, errors) {
  if (
    indexed.header.profile !== stream.header?.profile ||
    indexed.header.library !== stream.header?.library
  ) {
    errors.add("indexed reader: header differs from the stream reader's");
  }
  if (indexed.schemasById.size > 0) {
    for (const [id, schema] of stream.schemas) {
      const summary = indexed.schemasById.get(id);
      if (summary === undefined || !sameSchema(summary, schema)) {
        errors.add(`summary: schema ${id} missing or different from the data section's`);
      }
    }
  }
  if (indexed.channelsById.size > 0) {
    for (const [id, channel] of stream.channels) {
      const summary = indexed.channelsById.get(id);
      if (summary === undefined || !sameChannel(summary, channel)) {
        errors.add(`summary: channel ${id} (${channel.topic}) missing or different`);
      }
    }
  }
  for (const [id, schema] of indexed.schemasById) {
    if (!stream.schemas.has(id)) {
      errors.add(`summary: schema ${id} (${schema.name}) is not in the data section`);
    }
  }
  for (const [id, channel] of indexed.channelsById) {
    if (!stream.channels.has(id)) {
      // Allowed by the format (a channel that never got a message), so not an error.
      stream.summaryOnlyChannels.push(channel);
    }
  }
  const stats = indexed.statistics;
  if (stats !== undefined) {
    const checks = [
      ["message_count", Number(stats.messageCount), stream.messageCount],
      ["chunk_count", stats.chunkCount, stream.chunkCount],
      ["metadata_count", stats.metadataCount, stream.metadataNames.length],
      ["attachment_count", stats.attachmentCount, stream.attachmentCount],
      ["schema_count", stats.schemaCount, indexed.schemasById.size || stream.schemas.size],
      ["channel_count", stats.channelCount, indexed.channelsById.size || stream.channels.size],
    ];
    if (stream.messageCount > 0) {
      checks.push(["message_start_time", stats.messageStartTime, stream.minLogTime]);
      checks.push(["message_end_time", stats.messageEndTime, stream.maxLogTime]);
    }
    for (const [id, report] of stream.topics) {
      checks.push([
        `channel ${id} message count`,
        Number(stats.channelMessageCounts.get(id) ?? 0n),
        report.count,
      ]);
    }
    for (const [what, stated, seen] of checks) {
      if (stated !== seen) {
        errors.add(`statistics: ${what} is ${stated}, the file has ${seen}`);
      }
    }
  }
  if (indexed.chunkIndexes.length !== stream.chunkCount) {
    if (indexed.chunkIndexes.length > 0 || stream.messageCount === 0) {
      errors.add(
        `summary: ${indexed.chunkIndexes.length} chunk indexes for ${stream.chunkCount} chunks`,
      );
    }
    return null; // unchunked (or unindexed chunks): messages are not reachable through an index
  }
  if (stream.chunkCount === 0) {
    return null;
  }
  const remaining = new Map(stream.messageKeys);
  let count = 0;
  let previous;
  for await (const message of indexed.readMessages({ validateCrcs: true })) {
    ++count;
    if (previous !== undefined && message.logTime < previous) {
      errors.add("indexed reader: messages not in log time order");
    }
    previous = message.logTime;
    const key = messageKey(message);
    const left = remaining.get(key) ?? 0;
    if (left === 0) {
      errors.add("indexed reader: a message that the stream reader did not see");
    } else {
      remaining.set(key, left - 1);
    }
  }
  const missed = [...remaining.values()].reduce((a, b) => a + b, 0);
  if (missed > 0) {
    errors.add(
      `indexed reader: ${missed} messages of the data section not reached through the index`,
    );
  }
  return count;
}

async function main() {
  const args = process.argv.slice(2);
  if (args.length !== 1 || args[0].startsWith("-")) {
    process.stderr.write(kUsage + "\n");
    return 2;
  }
  const file = args[0];
  const errors = new Errors();
  await loadCompression();
  let handle;
  try {
    handle = await fs.open(file, "r");
  } catch (error) {
    process.stderr.write(`read_mcap: ${error.message}\n`);
    return 2;
  }
  const report = { file };
  try {
    const { size } = await handle.stat();
    const magic = Buffer.alloc(kMagic.length);
    await handle.read(magic, 0, magic.length, 0);
    if (!magic.equals(kMagic)) {
      errors.add("not an MCAP file (bad leading magic)");
    }

    const stream = newStreamState();
    try {
      await streamPass(handle, stream, errors);
    } catch (error) {
      errors.add(`stream reader: ${error.message}`);
    }

    let indexed;
    try {
      indexed = await McapIndexedReader.Initialize({
        readable: fileReadable(handle, size),
        decompressHandlers: kDecompressHandlers,
      });
    } catch (error) {
      if (!/File is not indexed/.test(error.message)) {
        errors.add(`indexed reader: ${error.message}`);
      }
    }
    await checkDataSectionCrc(handle, size, errors).catch((error) =>
      errors.add(`data section walk: ${error.message}`),
    );
    let indexedCount = null;
    if (indexed !== undefined && stream.complete) {
      try {
        indexedCount = await indexedPass(indexed, stream, errors);
      } catch (error) {
        errors.add(`indexed reader: ${error.message}`);
      }
    }
    const channels = [...stream.channels.values(), ...stream.summaryOnlyChannels];
    channels.sort((a, b) => a.id - b.id);
    Object.assign(report, {
      profile: stream.header?.profile ?? indexed?.header.profile ?? null,
      library: stream.header?.library ?? indexed?.header.library ?? null,
      indexed: indexed !== undefined,
      indexed_message_count: indexedCount,
      chunk_count: stream.chunkCount,
      compression: [...stream.compressions].sort(),
      metadata: stream.metadataNames,
      message_count: stream.messageCount,
      topics: channels.map((channel) => {
        const schema =
          stream.schemas.get(channel.schemaId) ?? indexed?.schemasById.get(channel.schemaId);
        return (stream.topics.get(channel.id) ?? new TopicReport(channel, schema)).toJson();
      }),
    });
  } finally {
    await handle.close();
  }
  report.errors = errors.list();
  process.stdout.write(JSON.stringify(report, null, 2) + "\n");
  for (const text of report.errors) {
    process.stderr.write(`read_mcap: ${text}\n`);
  }
  return report.errors.length === 0 ? 0 : 1;
}

process.exitCode = await main();
