// Test-only: reads a LAS file with the independent `copc` reader and prints
// what it sees as JSON on standard output: the header, the VLRs, the WKT
// and every point's dimensions. geoanchor's tests compare this with what
// geoanchor wrote. Usage: node verify.mjs FILE.las
import { readFileSync } from 'node:fs';
import { Las } from 'copc';

const file = process.argv[2];
const bytes = new Uint8Array(readFileSync(file));
const header = Las.Header.parse(bytes.subarray(0, 375));
const getter = async (begin, end) => bytes.subarray(begin, end);
const vlrs = await Las.Vlr.walk(getter, header);
const wktVlr = Las.Vlr.find(vlrs, 'LASF_Projection', 2112);
let wkt = null;
if (wktVlr) {
  const content = await Las.Vlr.fetch(getter, wktVlr);
  wkt = new TextDecoder().decode(content).replace(/\0+$/, '');
}
const count = Number(header.pointCount);
const start = header.pointDataOffset;
const data = bytes.subarray(start, start + count * header.pointDataRecordLength);
const view = Las.View.create(data, header);
const names = Object.keys(view.dimensions);
const getters = Object.fromEntries(names.map((n) => [n, view.getter(n)]));
const points = [];
for (let i = 0; i < view.pointCount; ++i) {
  points.push(names.map((n) => getters[n](i)));
}
process.stdout.write(JSON.stringify({
  header: { ...header, pointCount: count },
  vlrs: vlrs.map(({ userId, recordId, description, isExtended, contentLength }) =>
    ({ userId, recordId, description, isExtended, contentLength })),
  wkt,
  dimensions: names,
  points,
}));
