// SPDX-License-Identifier: BSD-3-Clause
// Writes a rosbag2 fixture (MCAP or SQLite) from a JSON-lines spec, serializing every message with
// @foxglove/rosmsg2-serialization and framing MCAP with @mcap/core, independently of raymap's code.

import { spawn } from "node:child_process";
import { once } from "node:events";
import { createReadStream } from "node:fs";
import fs from "node:fs/promises";
import path from "node:path";
import readline from "node:readline";
import { fileURLToPath } from "node:url";

import { parse as parseMsgDefinition } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import { LIBRARY_IDENTIFIER, McapWriter } from "@mcap/core";

import { loadCompression, makeChunkCompressor } from "./compression.mjs";
import { canonicalTypeName, fullDefinitionText } from "./definitions.mjs";

const kUsage = `usage: node write_bag.mjs SPEC.jsonl|- OUT [--storage mcap|sqlite3]
         [--compression none|zstd|lz4] [--chunk-size BYTES] [--unindexed] [--file-only]`;
const kRosDistro = "humble";
const kMetadataVersion = 5; // rosbag2_storage::BagMetadata::version in Humble
const kDefaultChunkSize = 1024 * 1024;
const kMaxUint64 = (1n << 64n) - 1n;

/** An error whose message says it all (bad command line, spec or tool): no stack trace. */
class ReportedError extends Error {}

function parseArgs(argv) {
  const options = {
    storage: "mcap",
    compression: undefined,
    chunkSize: undefined,
    unindexed: false,
    fileOnly: false,
  };
  const positional = [];
  for (let i = 0; i < argv.length; ++i) {
    const arg = argv[i];
    const value = () => {
      if (i + 1 >= argv.length) {
        throw new ReportedError(`${arg} needs a value`);
      }
      return argv[++i];
    };
    switch (arg) {
      case "--storage":
        options.storage = value();
        break;
      case "--compression":
        options.compression = value();
        break;
      case "--chunk-size": {
        const text = value();
        if (!/^\d+$/.test(text) || !Number.isSafeInteger(Number(text))) {
          throw new ReportedError(`--chunk-size takes a byte count, not "${text}"`);
        }
        options.chunkSize = Number(text);
        break;
      }
      case "--unindexed":
        options.unindexed = true;
        break;
      case "--file-only":
        options.fileOnly = true;
        break;
      case "-h":
      case "--help":
        process.stdout.write(kUsage + "\n");
        process.exit(0);
        break;
      default:
        if (arg.startsWith("-") && arg !== "-") {
          throw new ReportedError(`unknown option ${arg}`);
        }
        positional.push(arg);
    }
  }
  if (positional.length !== 2) {
    throw new ReportedError("expected SPEC.jsonl and OUT");
  }
  [options.spec, options.out] = positional;
  if (options.storage === "sqlite3") {
    if (options.compression !== undefined || options.chunkSize !== undefined || options.unindexed) {
      throw new ReportedError(
        "--compression, --chunk-size and --unindexed apply to --storage mcap",
      );
    }
  } else if (options.storage === "mcap") {
    options.compression ??= "none";
    options.chunkSize ??= kDefaultChunkSize;
    if (!["none", "zstd", "lz4"].includes(options.compression)) {
      throw new ReportedError(`unknown --compression ${options.compression}`);
    }
    if (options.chunkSize === 0 && options.compression !== "none") {
      throw new ReportedError("--compression needs chunks (--chunk-size > 0)");
    }
  } else {
    throw new ReportedError(`unknown --storage ${options.storage}`);
  }
  return options;
}

// ---------------------------------------------------------------------------------------------
// Spec parsing

/**
 * Puts quotes around integer literals of 16 digits or more outside strings, so that JSON.parse
 * keeps nanosecond times above 2^53 exact; the fields that take them accept digit strings.
 */
function quoteLongIntegers(line) {
  const stringBody = /(?:[^"\\]|\\.)*"/y; // from after an opening quote to the closing one
  const number = /-?\d+(\.\d+)?([eE][+-]?\d+)?/y;
  let out = "";
  let copied = 0;
  for (let i = 0; i < line.length; ) {
    const c = line[i];
    if (c === '"') {
      stringBody.lastIndex = i + 1;
      i = stringBody.exec(line) ? stringBody.lastIndex : line.length; // JSON.parse reports it
    } else if (c === "-" || (c >= "0" && c <= "9")) {
      number.lastIndex = i;
      const match = number.exec(line);
      if (match === null) {
        ++i;
        continue;
      }
      const token = match[0];
      if (!match[1] && !match[2] && token.replace("-", "").length >= 16) {
        out += line.slice(copied, i) + `"${token}"`;
        copied = i + token.length;
      }
      i += token.length;
    } else {
      ++i;
    }
  }
  return out + line.slice(copied);
}

/** A nanosecond time from a JSON number or digit string, as an exact bigint. */
function parseTimeNs(value, what) {
  const text = typeof value === "number" && Number.isInteger(value) ? String(value) : value;
  if (typeof text !== "string" || !/^\d+$/.test(text)) {
    throw new ReportedError(`${what} must be a non-negative integer (number or digit string)`);
  }
  const ns = BigInt(text);
  if (ns > kMaxUint64) {
    throw new ReportedError(`${what} does not fit in uint64`);
  }
  return ns;
}

// ---------------------------------------------------------------------------------------------
// Message values: spec JSON -> what MessageWriter serializes, checked against the definition

const kIntRanges = new Map([
  ["int8", [-(2n ** 7n), 2n ** 7n - 1n]],
  ["uint8", [0n, 2n ** 8n - 1n]],
  ["byte", [0n, 2n ** 8n - 1n]],
  ["char", [0n, 2n ** 8n - 1n]],
  ["int16", [-(2n ** 15n), 2n ** 15n - 1n]],
  ["uint16", [0n, 2n ** 16n - 1n]],
  ["int32", [-(2n ** 31n), 2n ** 31n - 1n]],
  ["uint32", [0n, 2n ** 32n - 1n]],
  ["int64", [-(2n ** 63n), 2n ** 63n - 1n]],
  ["uint64", [0n, kMaxUint64]],
]);

class MessageNormalizer {
  /** @param {import("@foxglove/message-definition").MessageDefinition[]} definitions */
  constructor(definitions) {
    this.root = definitions[0].definitions;
    this.byName = new Map(definitions.map((d) => [d.name ?? "", d.definitions]));
  }

  normalize(value) {
    return this.#struct(this.root, value, "msg");
  }

  #struct(fields, value, where) {
    const object = value ?? {};
    if (typeof object !== "object" || Array.isArray(object)) {
      throw new ReportedError(`${where}: expected an object`);
    }
    const names = new Set(fields.filter((f) => f.isConstant !== true).map((f) => f.name));
    for (const key of Object.keys(object)) {
      if (!names.has(key)) {
        throw new ReportedError(
          `${where}: unknown field "${key}" (fields: ${[...names].join(", ")})`,
        );
      }
    }
    const out = {};
    for (const field of fields) {
      if (field.isConstant !== true) {
        out[field.name] = this.#field(field, object[field.name], `${where}.${field.name}`);
      }
    }
    return out;
  }

  #field(field, value, where) {
    const element = (v, w) =>
      field.isComplex === true
        ? this.#struct(this.#definition(field.type), v, w)
        : this.#primitive(field.type, v, w);
    if (field.isArray !== true) {
      return field.isComplex === true || value !== undefined
        ? element(value, where)
        : this.#primitive(field.type, field.defaultValue, where);
    }
    if (value !== null && typeof value === "object" && "base64" in value) {
      return this.#base64(field, value, where);
    }
    if (value === undefined || value === null) {
      const length = field.arrayLength ?? 0;
      return Array.from({ length }, (_, i) => element(undefined, `${where}[${i}]`));
    }
    if (!Array.isArray(value)) {
      throw new ReportedError(`${where}: expected an array`);
    }
    if (field.arrayLength !== undefined && value.length !== field.arrayLength) {
      throw new ReportedError(`${where}: expected ${field.arrayLength} items, got ${value.length}`);
    }
    if (field.upperBound !== undefined && value.length > field.upperBound) {
      throw new ReportedError(`${where}: at most ${field.upperBound} items`);
    }
    return value.map((v, i) => element(v, `${where}[${i}]`));
  }

  #base64(field, value, where) {
    if (!["uint8", "int8", "byte", "char"].includes(field.type) || field.isComplex === true) {
      throw new ReportedError(`${where}: {"base64": ...} is only for byte arrays`);
    }
    const text = value.base64;
    if (Object.keys(value).length !== 1 || typeof text !== "string") {
      throw new ReportedError(`${where}: expected {"base64": "<string>"}`);
    }
    if (!/^[A-Za-z0-9+/]*={0,2}$/.test(text) || text.length % 4 !== 0) {
      throw new ReportedError(`${where}: not padded standard base64`);
    }
    const bytes = Buffer.from(text, "base64");
    if (field.arrayLength !== undefined && bytes.length !== field.arrayLength) {
      throw new ReportedError(`${where}: expected ${field.arrayLength} bytes, got ${bytes.length}`);
    }
    const copy = new Uint8Array(bytes); // a plain Uint8Array over its own buffer
    return field.type === "int8" ? new Int8Array(copy.buffer) : copy;
  }

  #definition(type) {
    const fields = this.byName.get(type);
    if (fields === undefined) {
      throw new Error(`definition of ${type} missing`);
    }
    return fields;
  }

  #primitive(type, value, where) {
    if (type === "time" || type === "duration") {
      const object = value ?? {};
      if (typeof object !== "object" || Array.isArray(object)) {
        throw new ReportedError(`${where}: expected {"sec": ..., "nanosec": ...}`);
      }
      for (const key of Object.keys(object)) {
        if (key !== "sec" && key !== "nanosec") {
          throw new ReportedError(`${where}: unknown field "${key}" (fields: sec, nanosec)`);
        }
      }
      return {
        sec: this.#primitive("int32", object.sec, `${where}.sec`),
        nanosec: this.#primitive("uint32", object.nanosec, `${where}.nanosec`),
      };
    }
    if (type === "bool") {
      if (value === undefined) {
        return false;
      }
      if (typeof value !== "boolean") {
        throw new ReportedError(`${where}: expected true or false`);
      }
      return value;
    }
    if (type === "string") {
      if (value === undefined) {
        return "";
      }
      // NOTE(harness): @foxglove/cdr sizes a string by its UTF-16 length, so only ASCII is exact.
      if (typeof value !== "string" || !/^[\x00-\x7f]*$/.test(value)) {
        throw new ReportedError(`${where}: expected an ASCII string`);
      }
      return value;
    }
    if (type === "float32" || type === "float64") {
      if (value === undefined) {
        return 0;
      }
      const special = { NaN: NaN, Infinity: Infinity, "-Infinity": -Infinity };
      if (typeof value === "string" && value in special) {
        return special[value];
      }
      if (typeof value === "string" && /^-?\d+$/.test(value)) {
        return Number(value); // a long integer literal, quoted by quoteLongIntegers
      }
      if (typeof value !== "number") {
        throw new ReportedError(`${where}: expected a number (or "NaN", "Infinity", "-Infinity")`);
      }
      return value;
    }
    const range = kIntRanges.get(type);
    if (range === undefined) {
      throw new ReportedError(`${where}: field type ${type} is not supported`);
    }
    if (value === undefined) {
      return type.endsWith("int64") ? 0n : 0;
    }
    const isInteger =
      (typeof value === "number" && Number.isInteger(value)) || typeof value === "bigint";
    const text = isInteger ? String(value) : value;
    if (typeof text !== "string" || !/^-?\d+$/.test(text)) {
      throw new ReportedError(`${where}: expected an integer`);
    }
    const integer = BigInt(text);
    if (integer < range[0] || integer > range[1]) {
      throw new ReportedError(`${where}: ${text} is out of range for ${type}`);
    }
    return type.endsWith("int64") ? integer : Number(integer);
  }
}

/** What one message type needs: schema text, parsed definition, writer and value checker. */
class TypeInfo {
  constructor(type) {
    this.name = canonicalTypeName(type);
    if (this.name === undefined) {
      throw new ReportedError(`"${type}" is not a ROS 2 type name`);
    }
    try {
      this.text = fullDefinitionText(this.name);
    } catch (error) {
      throw new ReportedError(error.message);
    }
    const definitions = parseMsgDefinition(this.text, { ros2: true });
    this.writer = new MessageWriter(definitions);
    this.normalizer = new MessageNormalizer(definitions);
  }

  serialize(value) {
    return this.writer.writeMessage(this.normalizer.normalize(value));
  }
}

// ---------------------------------------------------------------------------------------------
// Storage sinks

class McapSink {
  static async open(file, options) {
    const sink = new McapSink();
    sink.handle = await fs.open(file, "wx");
    let position = 0n;
    const handle = sink.handle;
    const writable = {
      async write(buffer) {
        for (let done = 0; done < buffer.byteLength; ) {
          const { bytesWritten } = await handle.write(buffer, done, buffer.byteLength - done);
          done += bytesWritten;
        }
        position += BigInt(buffer.byteLength);
      },
      position: () => position,
    };
    const chunked = options.chunkSize > 0;
    const indexed = !options.unindexed;
    sink.writer = new McapWriter({
      writable,
      useChunks: chunked,
      chunkSize: chunked ? options.chunkSize : undefined,
      compressChunk:
        chunked && options.compression !== "none"
          ? makeChunkCompressor(options.compression)
          : undefined,
      startChannelId: 1, // rosbag2's MCAP writer numbers channels from 1
      useMessageIndex: indexed,
      useChunkIndex: indexed,
      useStatistics: indexed,
      useSummaryOffsets: indexed,
      repeatSchemas: indexed,
      repeatChannels: indexed,
      useAttachmentIndex: indexed,
      useMetadataIndex: indexed,
    });
    sink.schemaIds = new Map();
    sink.channelIds = [];
    await sink.writer.start({
      profile: "ros2",
      library: `raymap tests/rosbag/node/write_bag.mjs; ${LIBRARY_IDENTIFIER}`,
    });
    // rosbag2 (Humble) writes this Metadata record when it opens an MCAP file.
    await sink.writer.addMetadata({
      name: "rosbag2",
      metadata: new Map([["ROS_DISTRO", kRosDistro]]),
    });
    return sink;
  }

  async addChannel({ topic, typeInfo, qos }) {
    let schemaId = this.schemaIds.get(typeInfo.name);
    if (schemaId === undefined) {
      schemaId = await this.writer.registerSchema({
        name: typeInfo.name,
        encoding: "ros2msg",
        data: new TextEncoder().encode(typeInfo.text),
      });
      this.schemaIds.set(typeInfo.name, schemaId);
    }
    this.channelIds.push(
      await this.writer.registerChannel({
        topic,
        schemaId,
        messageEncoding: "cdr",
        metadata: new Map([["offered_qos_profiles", qos]]),
      }),
    );
  }

  async addMessage(channelIndex, { logTime, publishTime, sequence, data }) {
    await this.writer.addMessage({
      channelId: this.channelIds[channelIndex],
      sequence,
      logTime,
      publishTime,
      data,
    });
  }

  async close() {
    await this.writer.end();
    await this.handle.close();
  }

  async abort() {
    await this.handle.close().catch(() => {});
  }
}

/**
 * Streams topics and serialized messages to write_db3.py on its stdin, in spec order:
 *   "RMDB3\n"; per topic 0x01, u32 length, JSON {name, type, serialization_format,
 *   offered_qos_profiles}; per message 0x02, u32 topic index (declaration order), i64 timestamp,
 *   u32 size, the CDR bytes; 0x00 at the end. Integers are little-endian.
 */
class Db3Sink {
  static async open(file) {
    const sink = new Db3Sink();
    const script = path.join(path.dirname(fileURLToPath(import.meta.url)), "write_db3.py");
    sink.child = spawn(
      process.env.PYTHON ?? "python3",
      [script, file, "--ros-distro", kRosDistro],
      {
        stdio: ["pipe", "inherit", "pipe"],
      },
    );
    sink.stderr = "";
    sink.child.stderr.setEncoding("utf8");
    sink.child.stderr.on("data", (text) => (sink.stderr += text));
    sink.spawnError = undefined;
    sink.exited = new Promise((resolve) => {
      sink.child.on("error", (error) => {
        sink.spawnError = error;
        resolve([null, null]);
      });
      sink.child.on("close", (code, signal) => resolve([code, signal])); // after stderr ends
    });
    sink.child.stdin.on("error", () => {}); // a dead child is reported from its exit status
    await sink.#write(Buffer.from("RMDB3\n"));
    return sink;
  }

  async #write(buffer) {
    try {
      if (this.spawnError === undefined && !this.child.stdin.write(buffer)) {
        await Promise.race([once(this.child.stdin, "drain"), this.exited]);
      }
    } catch {
      // EPIPE and the like: the exit status and stderr below say why.
    }
    if (this.spawnError !== undefined || this.child.exitCode !== null) {
      await this.#failed();
    }
  }

  async #failed() {
    const [code, signal] = await this.exited;
    if (this.spawnError !== undefined) {
      throw new ReportedError(`cannot run python3 for write_db3.py: ${this.spawnError.message}`);
    }
    throw new ReportedError(`write_db3.py failed (${code ?? signal}): ${this.stderr.trim()}`);
  }

  async addChannel({ topic, typeInfo, qos }) {
    const json = Buffer.from(
      JSON.stringify({
        name: topic,
        type: typeInfo.name,
        serialization_format: "cdr",
        offered_qos_profiles: qos,
      }),
    );
    const head = Buffer.alloc(5);
    head.writeUInt8(1, 0);
    head.writeUInt32LE(json.length, 1);
    await this.#write(Buffer.concat([head, json]));
  }

  async addMessage(topicIndex, { logTime, data }) {
    const head = Buffer.alloc(17);
    head.writeUInt8(2, 0);
    head.writeUInt32LE(topicIndex, 1);
    head.writeBigInt64LE(logTime, 5);
    head.writeUInt32LE(data.byteLength, 13);
    await this.#write(head);
    await this.#write(data);
  }

  async close() {
    await this.#write(Buffer.from([0]));
    this.child.stdin.end();
    const [code] = await this.exited;
    if (code !== 0) {
      await this.#failed();
    }
  }

  async abort() {
    this.child.stdin.destroy();
    this.child.kill();
    await this.exited;
  }
}

// ---------------------------------------------------------------------------------------------
// metadata.yaml

function yamlString(text) {
  const plain =
    /^[A-Za-z_/.][A-Za-z0-9_/.-]*$/.test(text) &&
    !/^(true|false|yes|no|on|off|null|y|n)$/i.test(text);
  return plain ? text : JSON.stringify(text);
}

/** rosbag2_bagfile_information laid out as yaml-cpp emits it for `ros2 bag record`. */
function metadataYaml({ storage, fileName, topics, counts, messageCount, start, end }) {
  const duration = messageCount > 0 ? end - start : 0n;
  const startNs = messageCount > 0 ? start : 0n;
  const lines = [
    "rosbag2_bagfile_information:",
    `  version: ${kMetadataVersion}`,
    `  storage_identifier: ${storage}`,
    "  duration:",
    `    nanoseconds: ${duration}`,
    "  starting_time:",
    `    nanoseconds_since_epoch: ${startNs}`,
    `  message_count: ${messageCount}`,
  ];
  if (topics.length === 0) {
    lines.push("  topics_with_message_count: []");
  } else {
    lines.push("  topics_with_message_count:");
    topics.forEach((topic, i) => {
      lines.push(
        "    - topic_metadata:",
        `        name: ${yamlString(topic.topic)}`,
        `        type: ${yamlString(topic.typeInfo.name)}`,
        "        serialization_format: cdr",
        `        offered_qos_profiles: ${yamlString(topic.qos)}`,
        `      message_count: ${counts[i]}`,
      );
    });
  }
  lines.push(
    '  compression_format: ""',
    '  compression_mode: ""',
    "  relative_file_paths:",
    `    - ${yamlString(fileName)}`,
    "  files:",
    `    - path: ${yamlString(fileName)}`,
    "      starting_time:",
    `        nanoseconds_since_epoch: ${startNs}`,
    "      duration:",
    `        nanoseconds: ${duration}`,
    `      message_count: ${messageCount}`,
  );
  return lines.join("\n") + "\n";
}

// ---------------------------------------------------------------------------------------------

async function writeBag(options, file, sink) {
  const topics = [];
  const topicIndex = new Map();
  const typeInfos = new Map();
  const counts = [];
  let messageCount = 0;
  let start = 0n;
  let end = 0n;

  const input = readline.createInterface({
    input:
      options.spec === "-" ? process.stdin : createReadStream(options.spec, { encoding: "utf8" }),
    crlfDelay: Infinity,
  });
  let lineNumber = 0;
  for await (const line of input) {
    ++lineNumber;
    if (line.trim() === "") {
      continue;
    }
    const at = `${options.spec}:${lineNumber}`;
    let record;
    try {
      record = JSON.parse(quoteLongIntegers(line));
    } catch (error) {
      throw new ReportedError(`${at}: not JSON: ${error.message}`);
    }
    try {
      if (record === null || typeof record !== "object" || Array.isArray(record)) {
        throw new ReportedError("expected a JSON object");
      }
      if (typeof record.topic !== "string" || record.topic === "") {
        throw new ReportedError('"topic" must be a non-empty string');
      }
      if (record.op === "channel") {
        checkKeys(record, ["op", "topic", "type", "qos"]);
        if (topicIndex.has(record.topic)) {
          throw new ReportedError(`topic ${record.topic} declared twice`);
        }
        if (typeof record.type !== "string") {
          throw new ReportedError('"type" must be a string');
        }
        const qos = record.qos ?? "";
        if (typeof qos !== "string") {
          throw new ReportedError('"qos" must be a string (offered_qos_profiles)');
        }
        const name = canonicalTypeName(record.type) ?? record.type;
        if (!typeInfos.has(name)) {
          typeInfos.set(name, new TypeInfo(record.type));
        }
        const topic = { topic: record.topic, typeInfo: typeInfos.get(name), qos };
        topicIndex.set(record.topic, topics.length);
        topics.push(topic);
        counts.push(0);
        await sink.addChannel(topic);
      } else if (record.op === "message") {
        checkKeys(record, ["op", "topic", "log_time_ns", "publish_time_ns", "sequence", "msg"]);
        const index = topicIndex.get(record.topic);
        if (index === undefined) {
          throw new ReportedError(`topic ${record.topic} has no "channel" line before it`);
        }
        const logTime = parseTimeNs(record.log_time_ns, "log_time_ns");
        const publishTime =
          record.publish_time_ns === undefined
            ? logTime
            : parseTimeNs(record.publish_time_ns, "publish_time_ns");
        const sequence = record.sequence ?? 0;
        if (!Number.isInteger(sequence) || sequence < 0 || sequence > 0xffffffff) {
          throw new ReportedError('"sequence" must be a uint32');
        }
        if (options.storage === "sqlite3" && logTime >= 1n << 63n) {
          throw new ReportedError("log_time_ns does not fit the INTEGER timestamp column");
        }
        const data = topics[index].typeInfo.serialize(record.msg);
        await sink.addMessage(index, { logTime, publishTime, sequence, data });
        counts[index] += 1;
        start = messageCount === 0 || logTime < start ? logTime : start;
        end = messageCount === 0 || logTime > end ? logTime : end;
        ++messageCount;
      } else {
        throw new ReportedError(`unknown "op" ${JSON.stringify(record.op)} (channel or message)`);
      }
    } catch (error) {
      throw error instanceof ReportedError ? new ReportedError(`${at}: ${error.message}`) : error;
    }
  }
  await sink.close();
  return {
    storage: options.storage,
    fileName: path.basename(file),
    topics,
    counts,
    messageCount,
    start,
    end,
  };
}

function checkKeys(record, allowed) {
  for (const key of Object.keys(record)) {
    if (!allowed.includes(key)) {
      throw new ReportedError(`unknown key "${key}" in a "${record.op}" line`);
    }
  }
}

async function main() {
  let options;
  try {
    options = parseArgs(process.argv.slice(2));
  } catch (error) {
    process.stderr.write(`write_bag: ${error.message}\n${kUsage}\n`);
    return 2;
  }
  const extension = options.storage === "mcap" ? ".mcap" : ".db3";
  let file;
  try {
    if (options.spec !== "-") {
      await fs.access(options.spec);
    }
    // Never write into or over something that exists: OUT is ours alone, and removed on failure.
    const exists = await fs.lstat(options.out).then(
      () => true,
      () => false,
    );
    if (exists) {
      throw new Error(`${options.out} exists`);
    }
    if (options.fileOnly) {
      file = options.out;
    } else {
      await fs.mkdir(options.out);
      file = path.join(options.out, `${path.basename(path.resolve(options.out))}_0${extension}`);
    }
  } catch (error) {
    process.stderr.write(`write_bag: ${error.message}\n`);
    return 1;
  }

  let sink;
  try {
    if (options.storage === "mcap") {
      await loadCompression();
      sink = await McapSink.open(file, options);
    } else {
      sink = await Db3Sink.open(file);
    }
    const summary = await writeBag(options, file, sink);
    if (!options.fileOnly) {
      await fs.writeFile(path.join(options.out, "metadata.yaml"), metadataYaml(summary));
    }
    return 0;
  } catch (error) {
    await sink?.abort();
    await fs.rm(options.out, { recursive: true, force: true });
    const text = error instanceof ReportedError ? error.message : (error?.stack ?? String(error));
    process.stderr.write(`write_bag: ${text}\n`);
    return 1;
  }
}

process.exitCode = await main();
