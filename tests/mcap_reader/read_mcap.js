#!/usr/bin/env node
// An independent reader of `ssta export --format mcap`: Foxglove's MCAP and ROS 2 libraries from
// the npm registry (package.json), nothing of SSTA's. Reads FILE.mcap, checks its structure (the
// magic at both ends, the chunk CRCs, the data section's and the summary's CRCs, the summary's
// statistics and chunk indexes against the records), decodes every message with the ros2msg
// schema the file carries, and prints a JSON summary on stdout. Exit status 1 on any failure.
//
//   node read_mcap.js FILE.mcap [--dump-map OUT.bin] [--picture OUT.png]
//
// --dump-map writes /map's cells (int8, row 0 the smallest y, as in the message); --picture
// draws /map's costs beside /traversability's class layer shaded by its elevation, with
// /sensor_path on top, from the decoded messages.
"use strict";

const fs = require("fs");
const zlib = require("zlib");
const { McapStreamReader, McapIndexedReader } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const { crc32 } = require("@foxglove/crc");
const fzstd = require("fzstd");

function fail(message) {
  process.stderr.write(`read_mcap: ${message}\n`);
  process.exit(1);
}

const args = process.argv.slice(2);
if (args.length < 1) fail("usage: read_mcap.js FILE.mcap [--dump-map OUT.bin] [--picture OUT.png]");
const file = args[0];
const option = (name) => {
  const i = args.indexOf(name);
  return i >= 0 ? args[i + 1] : undefined;
};

const decompressHandlers = {
  zstd: (data, size) => {
    const out = fzstd.decompress(data);
    if (BigInt(out.byteLength) !== size) throw new Error(`zstd chunk: ${out.byteLength} bytes, expected ${size}`);
    return out;
  },
};

// The structure, record by record, with every chunk's CRC checked.
function scan(bytes) {
  const magic = [0x89, 0x4d, 0x43, 0x41, 0x50, 0x30, 0x0d, 0x0a];
  const tail = bytes.subarray(bytes.length - 8);
  if (!magic.every((b, i) => bytes[i] === b && tail[i] === b)) throw new Error("no MCAP magic at both ends");
  const reader = new McapStreamReader({ includeChunks: true, decompressHandlers, validateCrcs: true });
  reader.append(bytes);
  const counts = {};
  const seen = { messages: 0, chunks: 0, chunkCrcs: 0, dataEndCrc: undefined, summaryRecords: 0 };
  for (let record; (record = reader.nextRecord()); ) {
    counts[record.type] = (counts[record.type] ?? 0) + 1;
    if (record.type === "Message") seen.messages += 1;
    if (record.type === "Chunk") {
      seen.chunks += 1;
      if (record.uncompressedCrc !== 0) seen.chunkCrcs += 1;
    }
    if (record.type === "DataEnd") seen.dataEndCrc = record.dataSectionCrc;
  }
  if (!reader.done()) throw new Error("the stream reader did not reach the closing magic");
  return { counts, seen };
}

class BufferReadable {
  constructor(bytes) {
    this.bytes = bytes;
  }
  async size() {
    return BigInt(this.bytes.length);
  }
  async read(offset, size) {
    return this.bytes.subarray(Number(offset), Number(offset + size));
  }
}

function png(width, height, rgb) {
  const table = (type, data) => {
    const head = Buffer.alloc(8);
    head.writeUInt32BE(data.length, 0);
    head.write(type, 4, "ascii");
    const crc = Buffer.alloc(4);
    crc.writeUInt32BE(crc32(Buffer.concat([head.subarray(4), data])) >>> 0, 0);
    return Buffer.concat([head, data, crc]);
  };
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0);
  ihdr.writeUInt32BE(height, 4);
  ihdr[8] = 8;  // bit depth
  ihdr[9] = 2;  // truecolour
  const raw = Buffer.alloc((3 * width + 1) * height);
  for (let r = 0; r < height; r++) {
    raw[r * (3 * width + 1)] = 0;
    Buffer.from(rgb.buffer, rgb.byteOffset + 3 * width * r, 3 * width).copy(raw, r * (3 * width + 1) + 1);
  }
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    table("IHDR", ihdr),
    table("IDAT", zlib.deflateSync(raw)),
    table("IEND", Buffer.alloc(0)),
  ]);
}

// /map's costs (white 0 .. black 100, unknown blue-grey) | /traversability's class layer (green
// traversable, blue semi, red non-traversable, grey undecided, black unknown) shaded by its
// elevation; /sensor_path in yellow on both. Each cell `scale` pixels.
function picture(map, gridMap, path) {
  const w = map.info.width, h = map.info.height, scale = Math.max(1, Math.min(6, Math.floor(900 / Math.max(w, h))));
  const gap = 8, W = (2 * w + 0) * scale + gap, H = h * scale;
  const rgb = new Uint8Array(3 * W * H).fill(255);
  const put = (x, y, c) => {
    if (x < 0 || y < 0 || x >= W || y >= H) return;
    rgb.set(c, 3 * (y * W + x));
  };
  const fill = (cx, cy, c) => {
    for (let dy = 0; dy < scale; dy++) for (let dx = 0; dx < scale; dx++) put(cx * scale + dx, cy * scale + dy, c);
  };
  for (let r = 0; r < h; r++) {
    for (let c = 0; c < w; c++) {
      const v = map.data[(h - 1 - r) * w + c];  // message row 0 is the smallest y
      const colour = v < 0 ? [150, 160, 180] : [255 - Math.round(2.55 * v), 255 - Math.round(2.55 * v), 255 - Math.round(2.55 * v)];
      fill(c, r, colour);
    }
  }
  const layer = (name) => gridMap.data[gridMap.layers.indexOf(name)].data;
  const cls = layer("class"), elevation = layer("elevation");
  const rows = gridMap.data[0].layout.dim[1].size;  // cells along x
  const cols = gridMap.data[0].layout.dim[0].size;  // cells along y
  let zmin = Infinity, zmax = -Infinity;
  for (const z of elevation) if (Number.isFinite(z)) (zmin = Math.min(zmin, z)), (zmax = Math.max(zmax, z));
  const colours = { 1: [60, 180, 75], 2: [0, 90, 220], 3: [220, 30, 30], 4: [128, 128, 128] };
  const xOffset = w * scale + gap;
  for (let j = 0; j < cols; j++) {
    for (let i = 0; i < rows; i++) {
      const k = i + j * rows;  // column-major
      const base = Number.isFinite(cls[k]) ? colours[cls[k]] ?? [255, 0, 255] : [0, 0, 0];
      const z = elevation[k];
      const shade = Number.isFinite(z) && zmax > zmin ? 0.6 + 0.4 * (z - zmin) / (zmax - zmin) : 1;
      const colour = base.map((b) => Math.round(b * shade));
      const r = j, c = rows - 1 - i;  // grid_map (i, j) grows towards -x, -y
      for (let dy = 0; dy < scale; dy++) for (let dx = 0; dx < scale; dx++) put(xOffset + c * scale + dx, r * scale + dy, colour);
    }
  }
  const res = map.info.resolution, ox = map.info.origin.position.x, oy = map.info.origin.position.y;
  for (const p of path.poses) {
    const c = (p.pose.position.x - ox) / res, r = h - (p.pose.position.y - oy) / res;
    if (c < 0 || c > w || r < 0 || r > h) continue;  // outside the grid
    for (const x0 of [0, xOffset]) {
      for (let dy = -2; dy <= 2; dy++) for (let dx = -2; dx <= 2; dx++) put(Math.round(x0 + c * scale) + dx, Math.round(r * scale) + dy, [255, 210, 0]);
    }
  }
  return png(W, H, rgb);
}

async function main() {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const { counts, seen } = scan(bytes);

  const reader = await McapIndexedReader.Initialize({ readable: new BufferReadable(bytes), decompressHandlers });
  // The data section's CRC: every byte from the start of the file up to the Data End record.
  const dataCrc = crc32(bytes.subarray(0, Number(reader.dataEndOffset)));
  if (reader.dataSectionCrc === undefined || reader.dataSectionCrc === 0) throw new Error("no data section CRC");
  if (dataCrc !== reader.dataSectionCrc) throw new Error(`data section CRC ${dataCrc} != ${reader.dataSectionCrc}`);
  if (reader.footer.summaryCrc === 0) throw new Error("no summary CRC");  // Initialize checked it
  const stats = reader.statistics;
  if (!stats) throw new Error("no Statistics record");
  if (Number(stats.messageCount) !== seen.messages) throw new Error("Statistics: message count differs from the records");
  if (stats.chunkCount !== seen.chunks || reader.chunkIndexes.length !== seen.chunks) {
    throw new Error("Statistics / Chunk Indexes: chunk count differs from the records");
  }
  if (seen.chunkCrcs !== seen.chunks) throw new Error("a chunk without CRC");
  if (stats.channelCount !== reader.channelsById.size || stats.schemaCount !== reader.schemasById.size) {
    throw new Error("Statistics: channel or schema count differs from the summary");
  }

  const decoders = new Map();
  const topics = {};
  for (const [id, channel] of reader.channelsById) {
    const schema = reader.schemasById.get(channel.schemaId);
    if (!schema || schema.encoding !== "ros2msg" || channel.messageEncoding !== "cdr") {
      throw new Error(`${channel.topic}: not a ros2msg schema with cdr messages`);
    }
    const definitions = parse(new TextDecoder().decode(schema.data), { ros2: true });
    decoders.set(id, new MessageReader(definitions));
    const qos = channel.metadata.get("offered_qos_profiles") ?? "";
    topics[channel.topic] = {
      type: schema.name,
      messages: Number(stats.channelMessageCounts.get(id) ?? 0n),
      latched: /durability: 1\b/.test(qos) && /reliability: 1\b/.test(qos),
    };
  }

  const decoded = {};
  let messages = 0;
  for await (const message of reader.readMessages()) {
    const channel = reader.channelsById.get(message.channelId);
    decoded[channel.topic] = decoders.get(message.channelId).readMessage(message.data);
    messages += 1;
  }
  if (messages !== seen.messages) throw new Error("the index gives another number of messages than the records");

  const summary = { file, bytes: bytes.length, records: counts, chunks: seen.chunks, messages, compression: [...new Set(reader.chunkIndexes.map((c) => c.compression || "none"))], topics };
  const map = decoded["/map"];
  if (map) {
    const values = { unknown: 0, occupied: 0, free: 0 };
    for (const v of map.data) values[v < 0 ? "unknown" : v >= 100 ? "occupied" : "free"] += 1;
    summary.map = {
      frame_id: map.header.frame_id, width: map.info.width, height: map.info.height, resolution: map.info.resolution,
      origin: [map.info.origin.position.x, map.info.origin.position.y, map.info.origin.position.z],
      cells: map.data.length, values,
    };
    if (option("--dump-map")) fs.writeFileSync(option("--dump-map"), Buffer.from(map.data.buffer, map.data.byteOffset, map.data.length));
  }
  const gridMap = decoded["/traversability"];
  if (gridMap) {
    summary.traversability = {
      frame_id: gridMap.header.frame_id, layers: gridMap.layers, basic_layers: gridMap.basic_layers,
      resolution: gridMap.info.resolution, length: [gridMap.info.length_x, gridMap.info.length_y],
      position: [gridMap.info.pose.position.x, gridMap.info.pose.position.y],
      layouts: gridMap.data.map((d) => d.layout.dim.map((dim) => [dim.label, dim.size, dim.stride])),
      cells: gridMap.data.map((d) => d.data.length),
      finite: gridMap.data.map((d) => d.data.filter(Number.isFinite).length),
      start_index: [gridMap.outer_start_index, gridMap.inner_start_index],
    };
  }
  const cloud = decoded["/traversability/voxels"];
  if (cloud) {
    summary.voxels = {
      frame_id: cloud.header.frame_id, points: cloud.width * cloud.height, point_step: cloud.point_step,
      fields: cloud.fields.map((f) => f.name), data_bytes: cloud.data.length,
    };
  }
  const path = decoded["/sensor_path"];
  if (path) summary.sensor_path = { frame_id: path.header.frame_id, poses: path.poses.length };
  const tf = decoded["/tf_static"];
  if (tf) summary.tf_static = tf.transforms.map((t) => [t.header.frame_id, t.child_frame_id]);
  if (option("--picture")) {
    if (!map || !gridMap || !path) throw new Error("--picture needs /map, /traversability and /sensor_path");
    fs.writeFileSync(option("--picture"), picture(map, gridMap, path));
  }
  process.stdout.write(JSON.stringify(summary, null, 1) + "\n");
}

main().catch((error) => fail(`${file}: ${error.message}`));
