// A small reader of binary little-endian PLY files with scalar properties (the 3DGS layout and what
// splat-transform writes), and of splat-transform's CSV output: both give
// { count, columns: Map<name, Float64Array> } for the first element ("vertex").
import { readFileSync } from 'node:fs';

const SIZES = {
  char: 1, uchar: 1, int8: 1, uint8: 1, short: 2, ushort: 2, int16: 2, uint16: 2,
  int: 4, uint: 4, int32: 4, uint32: 4, float: 4, float32: 4, double: 8, float64: 8,
};

function reader(view, type) {
  switch (type) {
    case 'char': case 'int8': return (o) => view.getInt8(o);
    case 'uchar': case 'uint8': return (o) => view.getUint8(o);
    case 'short': case 'int16': return (o) => view.getInt16(o, true);
    case 'ushort': case 'uint16': return (o) => view.getUint16(o, true);
    case 'int': case 'int32': return (o) => view.getInt32(o, true);
    case 'uint': case 'uint32': return (o) => view.getUint32(o, true);
    case 'float': case 'float32': return (o) => view.getFloat32(o, true);
    case 'double': case 'float64': return (o) => view.getFloat64(o, true);
    default: throw new Error(`unknown PLY type ${type}`);
  }
}

export function readPly(path) {
  const buf = readFileSync(path);
  const end = buf.indexOf('end_header\n');
  if (buf.subarray(0, 4).toString() !== 'ply\n' || end < 0) throw new Error(`${path}: not a PLY file`);
  const lines = buf.subarray(0, end).toString('latin1').split('\n');
  const elements = [];
  let format = '';
  for (const line of lines) {
    const w = line.trim().split(/\s+/);
    if (w[0] === 'format') format = w[1];
    else if (w[0] === 'element') elements.push({ name: w[1], count: Number(w[2]), props: [] });
    else if (w[0] === 'property') {
      if (w[1] === 'list') throw new Error(`${path}: list properties are not supported`);
      elements.at(-1).props.push({ type: w[1], name: w[2] });
    }
  }
  if (format !== 'binary_little_endian') throw new Error(`${path}: format ${format}, expected binary_little_endian`);
  const view = new DataView(buf.buffer, buf.byteOffset, buf.byteLength);
  let offset = end + 'end_header\n'.length;
  for (const el of elements) {
    const stride = el.props.reduce((s, p) => s + SIZES[p.type], 0);
    if (el.name === 'vertex') {
      const columns = new Map();
      let po = 0;
      for (const p of el.props) {
        const get = reader(view, p.type);
        const col = new Float64Array(el.count);
        for (let i = 0; i < el.count; ++i) col[i] = get(offset + i * stride + po);
        columns.set(p.name, col);
        po += SIZES[p.type];
      }
      if (offset + el.count * stride > buf.byteLength) throw new Error(`${path}: truncated`);
      return { count: el.count, columns, header: lines.join('\n') };
    }
    offset += el.count * stride;
  }
  throw new Error(`${path}: no vertex element`);
}

export function readCsv(path) {
  const lines = readFileSync(path, 'utf8').split(/\r?\n/).filter((l) => l.length > 0);
  const names = lines[0].split(',').map((s) => s.trim());
  const count = lines.length - 1;
  const columns = new Map(names.map((n) => [n, new Float64Array(count)]));
  for (let i = 0; i < count; ++i) {
    const v = lines[i + 1].split(',');
    if (v.length !== names.length) throw new Error(`${path}: row ${i + 1} has ${v.length} values, header ${names.length}`);
    names.forEach((n, k) => { columns.get(n)[i] = Number(v[k]); });
  }
  return { count, columns };
}

// The properties every 3DGS client needs (the reference layout, SH degree 3).
export const GAUSSIAN_PROPERTIES = [
  'x', 'y', 'z', 'f_dc_0', 'f_dc_1', 'f_dc_2',
  ...Array.from({ length: 45 }, (_, i) => `f_rest_${i}`),
  'opacity', 'scale_0', 'scale_1', 'scale_2', 'rot_0', 'rot_1', 'rot_2', 'rot_3',
];
