#!/usr/bin/env node
// An MCAP file made from an EuRoC-layout folder (real EuRoC or `ovton simulate` output) by a writer that is not
// ovton's: Foxglove's @mcap/core for the container, @foxglove/rosmsg2-serialization for ROS 2 CDR, pngjs to read the
// PNGs, jpeg-js to encode JPEGs. The file is what a ROS 2 recorder writes: profile ros2, ros2msg schemas, CDR
// messages, each message logged at a receive time a little after its header stamp (a recorder's clock) and written in
// receive order.
//
//   node write_mcap.mjs --folder DIR --out FILE.mcap [--images raw|jpeg|png] [--jpeg-quality Q]
//        [--compression zstd|none] [--chunk-kb N] [--no-index] [--dump-jpeg DIR] [--dither SEED] [--max-images N]
//
// raw: sensor_msgs/msg/Image mono8 on /cam0/image_raw; jpeg / png: sensor_msgs/msg/CompressedImage on
// /cam0/image_raw/compressed (png: the folder's own PNG bytes). --no-index: no summary, chunk or message index (what a
// recorder that stopped early leaves, without the cut). --dump-jpeg: also save each JPEG (write_db3.py reads them).
// --dither SEED: add -1, 0 or +1 grey level to each pixel before writing (raw or JPEG; seeded): a change below what a
// camera's noise makes, to measure how much a run's APE moves with any change of the pixels
// (scripts/experiments/mcap_compressed_ape.sh). --max-images N: the first N images only (the IMU log whole).
import fs from "node:fs";
import path from "node:path";
import { McapWriter } from "@mcap/core";
import { parse } from "@foxglove/rosmsg";
import { MessageWriter } from "@foxglove/rosmsg2-serialization";
import zstd from "@foxglove/wasm-zstd";
import { PNG } from "pngjs";
import jpeg from "jpeg-js";
import { SCHEMAS } from "./ros2_msgs.mjs";

function args() {
  const a = { images: "raw", jpegQuality: 95, compression: "zstd", chunkKb: 1024, index: true };
  const v = process.argv.slice(2);
  for (let i = 0; i < v.length; ++i) {
    const k = v[i];
    const next = () => {
      if (i + 1 >= v.length) throw new Error(`${k} needs a value`);
      return v[++i];
    };
    if (k === "--folder") a.folder = next();
    else if (k === "--out") a.out = next();
    else if (k === "--images") a.images = next();
    else if (k === "--jpeg-quality") a.jpegQuality = Number(next());
    else if (k === "--compression") a.compression = next();
    else if (k === "--chunk-kb") a.chunkKb = Number(next());
    else if (k === "--no-index") a.index = false;
    else if (k === "--dump-jpeg") a.dumpJpeg = next();
    else if (k === "--dither") a.dither = Number(next());
    else if (k === "--max-images") a.maxImages = Number(next());
    else throw new Error(`unknown option ${k}`);
  }
  if (!a.folder || !a.out) throw new Error("usage: write_mcap.mjs --folder DIR --out FILE.mcap [options]");
  if (!["raw", "jpeg", "png"].includes(a.images)) throw new Error(`--images ${a.images}: raw, jpeg or png`);
  if (!["zstd", "none"].includes(a.compression)) throw new Error(`--compression ${a.compression}: zstd or none`);
  if (a.dither !== undefined && a.images === "png") throw new Error("--dither applies to raw and jpeg images");
  return a;
}

/// Rows of an EuRoC csv file (CRLF or LF, '#' header lines).
function rows(file) {
  return fs
    .readFileSync(file, "utf8")
    .split("\n")
    .map((l) => l.replace(/\r$/, "").trim())
    .filter((l) => l.length > 0 && !l.startsWith("#"))
    .map((l) => l.split(",").map((s) => s.trim()));
}

function stamp(tNs) {
  return { sec: Number(tNs / 1000000000n), nanosec: Number(tNs % 1000000000n) };
}

/// The 8-bit gray pixels of a PNG (pngjs gives RGBA; a gray PNG has R = G = B).
function grayOf(png) {
  const out = Buffer.alloc(png.width * png.height);
  for (let i = 0; i < out.length; ++i) out[i] = png.data[4 * i];
  return out;
}

/// mulberry32: a small seeded generator, so that a dithered file is the same on every run.
function generator(seed) {
  let s = seed >>> 0;
  return () => {
    s = (s + 0x6d2b79f5) >>> 0;
    let t = s;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/// Adds -1, 0 or +1 to every grey level (clamped), in place on the RGBA pixels.
function dither(png, next) {
  for (let i = 0; i < png.width * png.height; ++i) {
    const g = Math.min(255, Math.max(0, png.data[4 * i] + Math.floor(next() * 3) - 1));
    png.data[4 * i] = png.data[4 * i + 1] = png.data[4 * i + 2] = g;
  }
}

class FileWritable {
  constructor(file) {
    this.fd = fs.openSync(file, "w");
    this.pos = 0n;
  }
  async write(buffer) {
    fs.writeSync(this.fd, buffer);
    this.pos += BigInt(buffer.byteLength);
  }
  position() {
    return this.pos;
  }
  close() {
    fs.closeSync(this.fd);
  }
}

async function main() {
  const a = args();
  await zstd.isLoaded;
  const mav0 = fs.existsSync(path.join(a.folder, "mav0")) ? path.join(a.folder, "mav0") : a.folder;
  const images = rows(path.join(mav0, "cam0", "data.csv"))
    .slice(0, a.maxImages)
    .map(([t, name]) => ({ t: BigInt(t), file: path.join(mav0, "cam0", "data", name) }));
  const imu = rows(path.join(mav0, "imu0", "data.csv")).map((r) => ({ t: BigInt(r[0]), v: r.slice(1, 7).map(Number) }));
  // A recorder's receive time: the IMU's readings 1 ms after their stamp, images 25 ms after (exposure, transfer).
  const events = [
    ...imu.map((u) => ({ kind: "imu", log: u.t + 1000000n, u })),
    ...images.map((im) => ({ kind: "image", log: im.t + 25000000n, im })),
  ].sort((x, y) => (x.log < y.log ? -1 : x.log > y.log ? 1 : 0));

  const writable = new FileWritable(a.out);
  const writer = new McapWriter({
    writable,
    chunkSize: a.chunkKb * 1024,
    useChunks: true,
    useStatistics: a.index,
    useSummaryOffsets: a.index,
    useChunkIndex: a.index,
    useMessageIndex: a.index,
    repeatSchemas: a.index,
    repeatChannels: a.index,
    compressChunk:
      a.compression === "zstd"
        ? (data) => ({ compression: "zstd", compressedData: zstd.compress(data, 3) })
        : undefined,
  });
  await writer.start({ profile: "ros2", library: "ovton scripts/mcap_tools/write_mcap.mjs (@mcap/core)" });
  const channel = async (topic, type) => {
    const schemaId = await writer.registerSchema({
      name: type,
      encoding: "ros2msg",
      data: new TextEncoder().encode(SCHEMAS[type]),
    });
    const id = await writer.registerChannel({
      topic,
      schemaId,
      messageEncoding: "cdr",
      metadata: new Map([["offered_qos_profiles", ""]]),
    });
    return { id, cdr: new MessageWriter(parse(SCHEMAS[type], { ros2: true })) };
  };
  const imageType = a.images === "raw" ? "sensor_msgs/msg/Image" : "sensor_msgs/msg/CompressedImage";
  const cam = await channel(a.images === "raw" ? "/cam0/image_raw" : "/cam0/image_raw/compressed", imageType);
  const imuCh = await channel("/imu0", "sensor_msgs/msg/Imu");
  if (a.dumpJpeg) fs.mkdirSync(a.dumpJpeg, { recursive: true });
  const zero9 = new Array(9).fill(0);
  const next = a.dither !== undefined ? generator(a.dither) : undefined;
  let sequence = 0;
  const counts = { images: 0, imu: 0 };
  for (const e of events) {
    let ch, msg;
    if (e.kind === "imu") {
      const [wx, wy, wz, ax, ay, az] = e.u.v;
      ch = imuCh;
      msg = {
        header: { stamp: stamp(e.u.t), frame_id: "imu0" },
        orientation: { x: 0, y: 0, z: 0, w: 1 },
        orientation_covariance: [-1, 0, 0, 0, 0, 0, 0, 0, 0],
        angular_velocity: { x: wx, y: wy, z: wz },
        angular_velocity_covariance: zero9,
        linear_acceleration: { x: ax, y: ay, z: az },
        linear_acceleration_covariance: zero9,
      };
      ++counts.imu;
    } else {
      const bytes = fs.readFileSync(e.im.file);
      const header = { stamp: stamp(e.im.t), frame_id: "cam0" };
      ch = cam;
      if (a.images === "png") {
        msg = { header, format: "png", data: bytes };
      } else {
        const png = PNG.sync.read(bytes);
        if (next) dither(png, next);
        if (a.images === "raw") {
          msg = { header, height: png.height, width: png.width, encoding: "mono8", is_bigendian: 0, step: png.width,
                  data: grayOf(png) };
        } else {
          const jpg = jpeg.encode({ data: png.data, width: png.width, height: png.height }, a.jpegQuality).data;
          if (a.dumpJpeg) fs.writeFileSync(path.join(a.dumpJpeg, path.basename(e.im.file, ".png") + ".jpg"), jpg);
          msg = { header, format: "jpeg", data: jpg };
        }
      }
      ++counts.images;
    }
    await writer.addMessage({
      channelId: ch.id,
      sequence: sequence++,
      logTime: e.log,
      publishTime: e.log,
      data: ch.cdr.writeMessage(msg),
    });
  }
  await writer.end();
  writable.close();
  console.log(JSON.stringify({ out: a.out, ...counts, bytes: Number(writable.position()) }));
}

main().catch((e) => {
  console.error(`write_mcap: ${e.message}`);
  process.exit(1);
});
