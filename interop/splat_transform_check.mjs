// @playcanvas/splat-transform reads our point_cloud.ply and converts it to PLY and to CSV; each converted
// file is read back and must hold the same Gaussians: the same count and every 3DGS property within
// float tolerance. Usage: node splat_transform_check.mjs OURS.ply WORKDIR  (prints one JSON line)
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdirSync, rmSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { GAUSSIAN_PROPERTIES, readCsv, readPly } from './ply.mjs';

const here = dirname(fileURLToPath(import.meta.url));
const cli = join(here, 'node_modules/@playcanvas/splat-transform/bin/cli.mjs');
const [ours, work] = process.argv.slice(2);
if (!ours || !work) { console.error('usage: splat_transform_check.mjs OURS.ply WORKDIR'); process.exit(2); }
rmSync(work, { recursive: true, force: true });
mkdirSync(work, { recursive: true });

const v = spawnSync('node', [cli, '--version'], { encoding: 'utf8' });
const version = `${v.stdout}${v.stderr}`.split('\n').find((l) => l.startsWith('splat-transform')) ?? 'unknown';
const reference = readPly(ours);

// Largest difference per property between our file and a converted one, relative to the value's
// magnitude (|a - b| / max(1, |a|)): float32 values written as float32 must match exactly, values
// printed as decimal text within float32 precision.
function compare(converted, tolerance) {
  const problems = [];
  let worst = { property: '', index: -1, error: 0 };
  if (converted.count !== reference.count) problems.push(`count ${converted.count}, ours ${reference.count}`);
  for (const name of GAUSSIAN_PROPERTIES) {
    const a = reference.columns.get(name);
    const b = converted.columns.get(name);
    if (!b) { problems.push(`property ${name} missing`); continue; }
    for (let i = 0; i < Math.min(a.length, b.length); ++i) {
      const err = Math.abs(a[i] - b[i]) / Math.max(1, Math.abs(a[i]));
      if (!(err <= worst.error)) worst = { property: name, index: i, error: err, ours: a[i], theirs: b[i] };
    }
  }
  if (worst.error > tolerance || Number.isNaN(worst.error)) problems.push(`${worst.property}[${worst.index}]: ours ${worst.ours}, converted ${worst.theirs}`);
  return { count: converted.count, max_relative_error: worst.error, worst, tolerance, ok: problems.length === 0, problems };
}

const results = { client: '@playcanvas/splat-transform', version, gaussians: reference.count, conversions: {} };
for (const [ext, read, tolerance] of [['ply', readPly, 0], ['csv', readCsv, 1e-6]]) {
  const out = join(work, `converted.${ext}`);
  execFileSync('node', [cli, '-q', '-w', ours, out], { stdio: ['ignore', 'inherit', 'inherit'] });
  results.conversions[ext] = { file: out, ...compare(read(out), tolerance) };
}
results.ok = Object.values(results.conversions).every((c) => c.ok);
console.log(JSON.stringify(results));
process.exit(results.ok ? 0 : 1);
