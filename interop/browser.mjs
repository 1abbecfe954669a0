// Headless Debian Chromium through playwright-core (never a downloaded browser), and a static file
// server on 127.0.0.1 for the pages: /node_modules/... and /interop/... from this folder, /data/...
// from a given folder.
import { createServer } from 'node:http';
import { readFile } from 'node:fs/promises';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { dirname, extname, join, normalize } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
export const CHROMIUM = process.env.CHROMIUM || '/usr/bin/chromium';
// The flags that work here as root without a GPU or a network (docs/interop.md).
export const CHROMIUM_FLAGS = [
  '--no-sandbox', '--disable-gpu', '--enable-unsafe-swiftshader', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
];

export async function launch() {
  const profile = mkdtempSync(join(tmpdir(), 'weathergs-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM, headless: true, args: CHROMIUM_FLAGS, deviceScaleFactor: 1,
    viewport: { width: 1280, height: 900 },
  });
  const version = context.browser() ? context.browser().version() : null;
  return {
    context, version,
    close: async () => { await context.close(); rmSync(profile, { recursive: true, force: true }); },
  };
}

const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json',
  '.wasm': 'application/wasm', '.png': 'image/png', '.css': 'text/css' };

export function serve(dataDir) {
  const server = createServer(async (req, res) => {
    const url = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    const rel = normalize(url).replace(/^\/+/, '');
    let file = null;
    if (rel.startsWith('data/')) file = join(dataDir, rel.slice(5));
    else if (rel.startsWith('node_modules/') || rel.startsWith('interop/')) file = join(here, rel.replace(/^interop\//, ''));
    if (!file || rel.includes('..')) { res.writeHead(404); res.end(); return; }
    try {
      const body = await readFile(file);
      res.writeHead(200, { 'Content-Type': TYPES[extname(file)] || 'application/octet-stream' });
      res.end(body);
    } catch {
      res.writeHead(404); res.end();
    }
  });
  return new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve({
    url: `http://127.0.0.1:${server.address().port}`, close: () => new Promise((r) => server.close(r)),
  })));
}
