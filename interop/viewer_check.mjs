// A Three.js splat viewer (@mkkellogg/gaussian-splats-3d) in headless Debian Chromium renders our
// point_cloud.ply from one dataset camera; its picture is compared with `weathergs render` of the same
// camera by `weathergs compare` (PSNR, bar: --min-psnr, default 25 dB).
// Usage: node viewer_check.mjs --weathergs BIN --ply RUN/point_cloud.ply --cameras DATA/cameras.json
//          --view NAME --ours RENDERS/NAME.png --out DIR [--min-psnr 25]
import { execFileSync } from 'node:child_process';
import { mkdirSync, readFileSync, writeFileSync, copyFileSync } from 'node:fs';
import { join } from 'node:path';
import { launch, serve } from './browser.mjs';

const args = {};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, '')] = process.argv[i + 1];
for (const k of ['weathergs', 'ply', 'cameras', 'view', 'ours', 'out'])
  if (!args[k]) { console.error(`viewer_check: --${k} is required`); process.exit(2); }
const minPsnr = Number(args['min-psnr'] ?? 25);
mkdirSync(args.out, { recursive: true });

const cameras = JSON.parse(readFileSync(args.cameras, 'utf8'));
const list = Array.isArray(cameras) ? cameras : cameras.views;
const cam = list.find((c) => c.name === args.view);
if (!cam) { console.error(`viewer_check: ${args.cameras}: no camera '${args.view}'`); process.exit(2); }
copyFileSync(args.ply, join(args.out, 'point_cloud.ply'));

const server = await serve(args.out);
const browser = await launch();
let result;
try {
  const page = await browser.context.newPage();
  const console_ = [];
  page.on('console', (m) => console_.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', (e) => console_.push(`pageerror: ${e.message}`));
  await page.goto(`${server.url}/interop/viewer.html`);
  await page.waitForFunction(() => window.viewerReady === true, null, { timeout: 60000 });
  const shDegree = Number(args.sh ?? 3);
  result = await page.evaluate(([url, c, sh]) => window.renderView(url, c, sh),
    [`${server.url}/data/point_cloud.ply`, cam, shDegree]);
  result.console = console_.slice(-20);
} finally {
  await browser.close();
  await server.close();
}
const viewerPng = join(args.out, `viewer_${args.view}.png`);
writeFileSync(viewerPng, Buffer.from(result.png.split(',')[1], 'base64'));
copyFileSync(args.ours, join(args.out, `weathergs_${args.view}.png`));
const cmp = JSON.parse(execFileSync(args.weathergs, ['--quiet', 'compare', viewerPng, args.ours, '--json'], { encoding: 'utf8' }));
const report = {
  client: '@mkkellogg/gaussian-splats-3d', version: JSON.parse(readFileSync(new URL('./node_modules/@mkkellogg/gaussian-splats-3d/package.json', import.meta.url))).version,
  three: JSON.parse(readFileSync(new URL('./node_modules/three/package.json', import.meta.url))).version,
  chromium: browser.version, webgl: result.gl, view: args.view, width: cam.width, height: cam.height,
  splats_in_viewer: result.splats, frames: result.frames, compare: cmp, min_psnr: minPsnr,
  ok: cmp.psnr >= minPsnr, screenshot: viewerPng, console: result.console.filter((l) => !l.includes("GL Driver Message")),
};
console.log(JSON.stringify(report));
process.exit(report.ok ? 0 : 1);
