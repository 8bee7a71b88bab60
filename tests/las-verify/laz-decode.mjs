// Test-only: decompresses a LAZ file with the independent decoder `laz-perf`
// (the LASzip codec compiled to WebAssembly) and writes the raw point
// records, back to back as an uncompressed LAS would hold them, to OUT.
// Prints one JSON line: what laz-perf read (point count, format, record
// length) and what `copc` reads of the same file with its own header, VLR
// and point-view code (copc decompresses through laz-perf too): the point
// count, the header's bounds, the bounds of the points' scaled X/Y/Z, the
// WKT. geoanchor's tests compare the records byte for byte.
// Usage: node laz-decode.mjs FILE.laz OUT.bin
import { readFileSync, writeFileSync } from 'node:fs';
import { createLazPerf } from 'laz-perf';
import { Las } from 'copc';

const [file, out] = process.argv.slice(2);
const bytes = new Uint8Array(readFileSync(file));

const LazPerf = await createLazPerf();
const filePtr = LazPerf._malloc(bytes.byteLength);
LazPerf.HEAPU8.set(bytes, filePtr);
const laszip = new LazPerf.LASZip();
laszip.open(filePtr, bytes.byteLength);
const count = laszip.getCount();
const length = laszip.getPointLength();
const format = laszip.getPointFormat();
const pointPtr = LazPerf._malloc(length);
const records = new Uint8Array(count * length);
for (let i = 0; i < count; ++i) {
  laszip.getPoint(pointPtr);
  records.set(LazPerf.HEAPU8.subarray(pointPtr, pointPtr + length), i * length);
}
laszip.delete();
LazPerf._free(pointPtr);
LazPerf._free(filePtr);
writeFileSync(out, records);

// The second reader: copc's header, VLRs and point view.
const header = Las.Header.parse(bytes.subarray(0, 375));
const getter = async (begin, end) => bytes.subarray(begin, end);
const vlrs = await Las.Vlr.walk(getter, header);
const wktVlr = Las.Vlr.find(vlrs, 'LASF_Projection', 2112);
let wkt = null;
if (wktVlr) wkt = new TextDecoder().decode(await Las.Vlr.fetch(getter, wktVlr)).replace(/\0+$/, '');
const data = await Las.PointData.decompressFile(bytes);
const view = Las.View.create(data, header);
const xyz = ['X', 'Y', 'Z'].map((d) => view.getter(d));
const lo = [Infinity, Infinity, Infinity];
const hi = [-Infinity, -Infinity, -Infinity];
for (let i = 0; i < view.pointCount; ++i) {
  for (let k = 0; k < 3; ++k) {
    const v = xyz[k](i);
    lo[k] = Math.min(lo[k], v);
    hi[k] = Math.max(hi[k], v);
  }
}
process.stdout.write(JSON.stringify({
  count, format, length,
  copc: {
    pointCount: Number(header.pointCount),
    headerMin: header.min,
    headerMax: header.max,
    pointsMin: lo,
    pointsMax: hi,
    wkt,
  },
}) + '\n');
