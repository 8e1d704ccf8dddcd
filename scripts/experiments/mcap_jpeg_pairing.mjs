#!/usr/bin/env node
// Checks the pairing of scripts/experiments/mcap_jpeg_paired_ape.sh: for one dither seed, the JPEG file's images are
// the JPEG encoding of the raw file's (dithered) pixels, not of other pixels. Reads the raw MCAP (write_mcap.mjs
// --images raw --compression none --dither SEED) with @mcap/core and Foxglove's CDR decoder, encodes every image
// again with jpeg-js at quality Q and compares the bytes with the JPEGs that write_mcap.mjs --images jpeg --dither SEED
// --dump-jpeg DIR wrote; also checks that each dithered pixel is within 1 grey level of the folder's PNG.
//
//   node mcap_jpeg_pairing.mjs TOOLS_DIR FOLDER RAW.mcap JPEG_DIR Q
// Prints one line; exits 1 when an image differs.
import fs from "node:fs";
import path from "node:path";
import { createRequire } from "node:module";
import { FileReadable } from "../mcap_tools/file_readable.mjs";

const [tools, folder, rawFile, jpegDir, q] = process.argv.slice(2);
const require = createRequire(path.resolve(tools, "package.json"));
const { McapIndexedReader } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const jpeg = require("jpeg-js");
const { PNG } = require("pngjs");

const mav0 = fs.existsSync(path.join(folder, "mav0")) ? path.join(folder, "mav0") : folder;
const names = new Map(
  fs.readFileSync(path.join(mav0, "cam0", "data.csv"), "utf8").split("\n")
    .filter((l) => l && !l.startsWith("#"))
    .map((l) => l.split(",").map((s) => s.trim()))
    .map(([t, name]) => [t, name]),
);
const reader = await McapIndexedReader.Initialize({ readable: new FileReadable(rawFile) });
let cdr;
for (const [, ch] of reader.channelsById)
  if (ch.topic === "/cam0/image_raw")
    cdr = new MessageReader(parse(new TextDecoder().decode(reader.schemasById.get(ch.schemaId).data), { ros2: true }));
let images = 0, same = 0, dithered = 0, pixels = 0, maxDev = 0;
for await (const m of reader.readMessages({ topics: ["/cam0/image_raw"] })) {
  const img = cdr.readMessage(m.data);
  const t = (BigInt(img.header.stamp.sec) * 1000000000n + BigInt(img.header.stamp.nanosec)).toString();
  const name = names.get(t);
  const png = PNG.sync.read(fs.readFileSync(path.join(mav0, "cam0", "data", name)));
  const rgba = Buffer.alloc(4 * img.width * img.height);
  for (let i = 0; i < img.width * img.height; ++i) {
    const g = img.data[i];
    rgba[4 * i] = rgba[4 * i + 1] = rgba[4 * i + 2] = g;
    rgba[4 * i + 3] = png.data[4 * i + 3];
    const d = Math.abs(g - png.data[4 * i]);
    maxDev = Math.max(maxDev, d);
    if (d) ++dithered;
    ++pixels;
  }
  const again = jpeg.encode({ data: rgba, width: img.width, height: img.height }, Number(q)).data;
  const written = fs.readFileSync(path.join(jpegDir, path.basename(name, ".png") + ".jpg"));
  if (Buffer.compare(again, written) === 0) ++same;
  ++images;
}
console.log(`${images} images: JPEG of the raw file's pixels byte-identical to the JPEG file's in ${same}; ` +
  `${(100 * dithered / pixels).toFixed(1)} % of pixels dithered, at most ${maxDev} grey level from the PNG`);
process.exit(same === images && images > 0 && maxDev <= 1 ? 0 : 1);
