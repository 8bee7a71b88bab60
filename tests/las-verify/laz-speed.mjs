// Benchmark helper (bench/apply_bench.cpp runs it in a child process):
// decompresses every point of FILE with laz-perf (the LASzip codec compiled
// to WebAssembly), RUNS times, each point copied out as laz-perf's own
// readers do, and prints one JSON line: the point count, the record length
// and the seconds of each run, timed inside the script (Node's and the
// WebAssembly module's start-up and the file read are not in them).
// Usage: node laz-speed.mjs FILE.laz [RUNS]
import { readFileSync } from 'node:fs';
import { createLazPerf } from 'laz-perf';

const [file, runsText] = process.argv.slice(2);
const runs = Number(runsText ?? 1);
const bytes = new Uint8Array(readFileSync(file));
const LazPerf = await createLazPerf();
const filePtr = LazPerf._malloc(bytes.byteLength);
LazPerf.HEAPU8.set(bytes, filePtr);

const seconds = [];
let count = 0;
let length = 0;
let checksum = 0;
for (let r = 0; r < runs; ++r) {
  const t0 = process.hrtime.bigint();
  const laszip = new LazPerf.LASZip();
  laszip.open(filePtr, bytes.byteLength);
  count = laszip.getCount();
  length = laszip.getPointLength();
  const pointPtr = LazPerf._malloc(length);
  for (let i = 0; i < count; ++i) {
    laszip.getPoint(pointPtr);
    checksum = (checksum + LazPerf.HEAPU8[pointPtr]) & 0xffff;  // the points are used
  }
  laszip.delete();
  LazPerf._free(pointPtr);
  seconds.push(Number(process.hrtime.bigint() - t0) / 1e9);
}
LazPerf._free(filePtr);
process.stdout.write(JSON.stringify({ count, length, seconds, checksum }) + '\n');
