// A local file as @mcap/core's McapIndexedReader reads it (size and random reads), shared by the tools that read MCAP
// files with Foxglove's reader.
import fs from "node:fs";

export class FileReadable {
  constructor(file) {
    this.fd = fs.openSync(file, "r");
    this.bytes = BigInt(fs.fstatSync(this.fd).size);
  }
  async size() {
    return this.bytes;
  }
  async read(offset, length) {
    const out = new Uint8Array(Number(length));
    fs.readSync(this.fd, out, 0, out.length, Number(offset));
    return out;
  }
}
