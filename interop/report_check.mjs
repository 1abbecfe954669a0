// The static report (`weathergs report SUITE -o REPORT`) opened from file:// in headless Chromium:
// no console errors, warnings or network requests; every image loads and every relative link exists;
// every per-view metric on the page equals its runs/<variant>/<method>/seed<S>/results.json (exact
// number in data-value, rounded as shown); the tables show data.js; sorting, the synchronized zoom,
// the toggles and the curve tooltips work; a full-page screenshot.
// Usage: node report_check.mjs REPORT_DIR SUITE_DIR OUT_PNG
import { existsSync, readFileSync, readdirSync, mkdirSync } from 'node:fs';
import { dirname, join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import vm from 'node:vm';
import { launch } from './browser.mjs';

const [reportArg, suiteArg, outPng] = process.argv.slice(2);
if (!reportArg || !suiteArg || !outPng) { console.error('usage: report_check.mjs REPORT_DIR SUITE_DIR OUT_PNG'); process.exit(2); }
const reportDir = resolve(reportArg), suiteDir = resolve(suiteArg);
mkdirSync(dirname(resolve(outPng)), { recursive: true });
const problems = [];
const DIGITS = { psnr: 2, ssim: 4, lpips: 4 };
const DASH = '–';
const isNumber = (v) => typeof v === 'number' && Number.isFinite(v);
const dataValue = (v) => (isNumber(v) ? String(v) : 'null');

// data.js, run as the page runs it, for what the page must show and the files it names.
const sandbox = { window: {} };
vm.runInNewContext(readFileSync(join(reportDir, 'data.js'), 'utf8'), sandbox, { filename: 'data.js' });
const data = sandbox.window.WEATHERGS_REPORT;
if (!data || data.format !== 'weathergs-report') { console.error('report_check: data.js holds no weathergs report'); process.exit(2); }

// The results files: "<variant>/<method>/seed<S>" -> per_view.
const results = new Map();
const runsDir = join(suiteDir, 'runs');
const dirs = (d) => (existsSync(d) ? readdirSync(d, { withFileTypes: true }).filter((e) => e.isDirectory()).map((e) => e.name) : []);
for (const variant of dirs(runsDir))
  for (const method of dirs(join(runsDir, variant)))
    for (const seed of dirs(join(runsDir, variant, method)).filter((s) => /^seed\d+$/.test(s))) {
      const file = join(runsDir, variant, method, seed, 'results.json');
      if (existsSync(file)) results.set(`${variant}/${method}/${seed}`, { file, used: 0, ...JSON.parse(readFileSync(file, 'utf8')) });
    }
if (results.size === 0) problems.push(`${runsDir}: no results.json files`);

// Every file data.js names must be in the report folder.
const named = [];
for (const v of data.variants || [])
  for (const view of v.views || []) {
    for (const cell of Object.values(view.cells || {})) named.push(cell.thumb, cell.full, cell.diff);
    named.push(...Object.values(view.overlays || {}));
  }
for (const path of named.filter(Boolean))
  if (!existsSync(join(reportDir, path))) problems.push(`data.js names ${path}: not in ${reportDir}`);

const browser = await launch();
const messages = [];
const report = {};  // filled as the checks go, so that a stopped check still says how far it got
try {
  const page = await browser.context.newPage();
  page.setDefaultTimeout(20000);
  page.on('console', (m) => { if (m.type() === 'error' || m.type() === 'warning') messages.push(`${m.type()}: ${m.text()}`); });
  page.on('pageerror', (e) => messages.push(`pageerror: ${e.message}`));
  page.on('requestfailed', (r) => messages.push(`request failed: ${r.url()} (${r.failure()?.errorText})`));
  page.on('request', (r) => { if (!/^(file|data):/.test(r.url())) messages.push(`network request: ${r.url()}`); });
  await page.goto(pathToFileURL(join(reportDir, 'index.html')).href);
  const imagesSettled = () => page.waitForFunction(() => [...document.images].every((i) => i.complete), null, { timeout: 30000 });
  const brokenImages = () => page.evaluate(() => [...document.images]
    .filter((i) => !(i.complete && i.naturalWidth > 0)).map((i) => i.getAttribute('src')));
  await imagesSettled();
  const images = report.images = await page.evaluate(() => document.images.length);
  for (const src of await brokenImages()) problems.push(`image not loaded: ${src}`);

  // Links: fragments must name an element; other links must be relative and exist on disk.
  const links = await page.evaluate(() => [...document.querySelectorAll('a[href]')].map((a) => {
    const href = a.getAttribute('href');
    return { href, target: href.startsWith('#') ? !!document.getElementById(decodeURIComponent(href.slice(1))) : null };
  }));
  report.links = links.length;
  for (const { href, target } of links) {
    if (href.startsWith('#')) { if (!target) problems.push(`link ${href}: no such element`); continue; }
    if (/^[a-z][a-z0-9+.-]*:/i.test(href) || href.startsWith('/')) { problems.push(`link ${href}: not relative`); continue; }
    const file = join(reportDir, decodeURIComponent(href.replace(/[?#].*$/, '')));
    if (!existsSync(file)) problems.push(`link ${href}: ${file} does not exist`);
  }

  // Per-view metrics against the results files.
  const metrics = await page.evaluate(() => [...document.querySelectorAll('[data-metric]')].map((n) => ({
    variant: n.dataset.variant, view: n.dataset.view, column: n.dataset.column, metric: n.dataset.metric,
    value: n.dataset.value, text: n.textContent.trim() })));
  let perViewChecked = 0;
  for (const m of metrics) {
    const where = `${m.variant} / ${m.view} / ${m.column} / ${m.metric}`;
    const [, method, seed] = /^(.*)\/seed(\d+)$/.exec(m.column) || [];
    const r = method && results.get(`${m.variant}/${method}/seed${seed}`);
    const pv = r && r.per_view && r.per_view[m.view];
    if (!pv || !(m.metric in pv)) { problems.push(`${where}: no such value in any results.json`); continue; }
    const expected = pv[m.metric];
    const shown = isNumber(expected) ? expected.toFixed(DIGITS[m.metric]) : DASH;
    const exact = isNumber(expected) ? isNumber(Number(m.value)) && Math.abs(Number(m.value) - expected) <= 1e-12 : m.value === 'null';
    if (!exact) problems.push(`${where}: data-value ${m.value}, ${r.file} has ${expected}`);
    if (m.text !== shown) problems.push(`${where}: shows '${m.text}', expected '${shown}'`);
    ++r.used; ++perViewChecked;
  }
  report.per_view_checked = perViewChecked;
  if (perViewChecked === 0) problems.push('no per-view metric on the page');
  for (const r of results.values()) if (r.used === 0) problems.push(`${r.file}: none of its values is on the page`);

  // Tables (before any sorting, rows are in data.js order): values, texts, bold only on the best
  // non-reference value of a "better" column.
  const tableIds = (data.tables || []).map((t) => t.id);
  const domTables = await page.evaluate(() => Object.fromEntries([...document.querySelectorAll('table[data-table-id]')].map((t) =>
    [t.dataset.tableId, [...t.querySelectorAll('tbody tr')].map((tr) => Object.fromEntries([...tr.querySelectorAll('td[data-key]')].map((td) => {
      const copy = td.cloneNode(true);
      copy.querySelectorAll('.ref-tag').forEach((n) => n.remove());
      return [td.dataset.key, { value: td.dataset.value ?? null, text: copy.textContent.trim(), bold: td.classList.contains('best') }];
    })))])));
  let tableCellsChecked = 0;
  const checkTable = (id, table) => {
    const dom = domTables[id];
    if (!dom) { problems.push(`table ${id}: not on the page`); return; }
    if (dom.length !== table.rows.length) problems.push(`table ${id}: ${dom.length} rows, data.js has ${table.rows.length}`);
    for (const c of table.columns) {
      const good = table.rows.filter((r) => !r.reference).map((r) => r.cells[c.key]?.value).filter(isNumber);
      const best = c.better === 'higher' ? Math.max(...good) : c.better === 'lower' ? Math.min(...good) : null;
      table.rows.forEach((row, i) => {
        const cell = row.cells[c.key] || {}, got = dom[i]?.[c.key];
        const where = `table ${id} / ${row.method ?? i} / ${c.key}`;
        if (!got) { problems.push(`${where}: no cell`); return; }
        if ('value' in cell && got.value !== dataValue(cell.value)) problems.push(`${where}: data-value ${got.value}, data.js ${cell.value}`);
        if (cell.text !== undefined && got.text !== cell.text) problems.push(`${where}: shows '${got.text}', data.js '${cell.text}'`);
        const shouldBold = !row.reference && best !== null && good.length > 0 && cell.value === best;
        if (got.bold !== shouldBold) problems.push(`${where}: ${got.bold ? 'bold' : 'not bold'}`);
        ++tableCellsChecked;
      });
    }
  };
  for (const t of data.tables || []) checkTable(t.id, t);
  for (const t of (data.converged || {}).tables || []) checkTable(t.id, t);  // the archive's, beside
  if (data.cost && (data.cost.rows || []).length) checkTable('cost', data.cost);

  // Sorting: a numeric column of the first leaderboard table, ascending then descending (or the
  // other way round); missing values stay last.
  report.table_cells_checked = tableCellsChecked;
  const sort = report.sort = { table: tableIds[0] ?? null };
  if (sort.table === null) problems.push('no leaderboard table to sort');
  else {
    const rows0 = domTables[sort.table] || [];
    const numericKey = (data.tables[0].columns || []).map((c) => c.key).find((k) =>
      new Set(rows0.map((r) => r[k]?.value).filter((v) => v && v !== 'null')).size >= 2);
    sort.key = numericKey ?? null;
    if (!numericKey) problems.push(`table ${sort.table}: no numeric column to sort`);
    else {
      const read = () => page.evaluate(([id, key]) => {
        const table = [...document.querySelectorAll('table[data-table-id]')].find((t) => t.dataset.tableId === id);
        return [...table.querySelectorAll('tbody tr')].map((tr) =>
          [...tr.querySelectorAll('td[data-key]')].find((td) => td.dataset.key === key).dataset.value);
      }, [sort.table, numericKey]);
      const header = page.locator(`table[data-table-id="${sort.table}"] th[data-key="${numericKey}"]`);
      const direction = (list) => {
        const nums = list.filter((v) => v !== 'null').map(Number);
        if (list.slice(nums.length).some((v) => v !== 'null')) return 'missing values not last';
        const up = nums.every((v, i) => i === 0 || nums[i - 1] <= v), down = nums.every((v, i) => i === 0 || nums[i - 1] >= v);
        return up && !down ? 'ascending' : down && !up ? 'descending' : 'unsorted';
      };
      await header.click();
      sort.first = direction(await read());
      await header.click();
      sort.second = direction(await read());
      const ok = ['ascending', 'descending'].includes(sort.first) && ['ascending', 'descending'].includes(sort.second) && sort.first !== sort.second;
      if (!ok) problems.push(`table ${sort.table} sorted by ${numericKey}: ${sort.first}, then ${sort.second}`);
    }
  }

  // Zoom: a click on the first image of the first view row, then on its last image near a corner;
  // every tile of the row's strip must show the same crop of its own column's full image.
  const zoom = report.zoom = {};
  const variant = (data.variants || [])[0];
  if (!variant || !(variant.views || []).length) problems.push('no variant with views to zoom');
  else {
    const view = variant.views[0], W = variant.width, H = variant.height, size = Math.min(48, W, H);
    zoom.row = `${variant.name}/${view.name}`;
    const rowImages = page.locator(`table.grid[data-variant="${variant.name}"] tr.view-row`).first().locator('a.thumb img:not(.overlay)');
    const clamp = (v, lo, hi) => Math.min(Math.max(v, lo), hi);
    zoom.clicks = [];
    for (const [which, fx, fy] of [['first', 0.3, 0.6], ['last', 0.97, 0.03]]) {
      const img = which === 'first' ? rowImages.first() : rowImages.last();
      const box = await img.boundingBox();
      await img.click({ position: { x: fx * box.width, y: fy * box.height } });
      const tiles = await page.evaluate((name) => {
        const row = [...document.querySelectorAll('[data-zoom-row]')].find((n) => n.getAttribute('data-zoom-row') === name);
        if (!row) return null;
        return { visible: row.offsetParent !== null, tiles: [...row.querySelectorAll('[data-crop]')].map((t) => ({
          crop: t.dataset.crop, column: t.dataset.column, background: getComputedStyle(t).backgroundImage })) };
      }, zoom.row);
      const want = [clamp(Math.round(fx * W - size / 2), 0, W - size), clamp(Math.round(fy * H - size / 2), 0, H - size), size, size];
      const crops = [...new Set((tiles?.tiles || []).map((t) => t.crop))];
      zoom.clicks.push({ image: which, tiles: tiles?.tiles.length ?? 0, crops });
      if (!tiles || !tiles.visible) { problems.push(`zoom ${zoom.row}: no visible zoom strip after a click`); continue; }
      if (tiles.tiles.length !== variant.columns.length) problems.push(`zoom ${zoom.row}: ${tiles.tiles.length} tiles for ${variant.columns.length} columns`);
      if (crops.length !== 1) { problems.push(`zoom ${zoom.row}: tiles disagree: ${crops.join(' | ')}`); continue; }
      const crop = crops[0].split(',').map(Number);
      if (!(crop.length === 4 && crop.every(Number.isInteger) && crop.every((v, i) => Math.abs(v - want[i]) <= 1)))
        problems.push(`zoom ${zoom.row} (${which} image): crop ${crops[0]}, expected about ${want.join(',')}`);
      for (const t of tiles.tiles) {
        const full = view.cells[t.column]?.full;
        const encoded = full && full.split('/').map(encodeURIComponent).join('/');
        if (!full || !t.background.includes(encoded)) problems.push(`zoom ${zoom.row} / ${t.column}: tile does not show ${full}`);
      }
    }
  }

  // Toggles of the first variant (difference images, every overlay): the new images load too.
  if (variant) {
    const boxes = page.locator(`section[id="variant-${variant.name}"] .controls input[type=checkbox]`);
    report.toggles = await boxes.count();
    for (let i = 0; i < report.toggles; ++i) await boxes.nth(i).check();
    await imagesSettled();
    for (const src of await brokenImages()) problems.push(`image not loaded after the toggles: ${src}`);
    const shown = await page.locator(`section[id="variant-${variant.name}"] img.overlay:not([hidden])`).count();
    if ((variant.overlays || []).length && shown === 0) problems.push(`${variant.name}: overlays checked but none shown`);
  }

  // Curves: one marker (with a <title>) per usable point; hovering one shows the tooltip.
  const points = (data.curves || []).flatMap((c) => (c.points || []).filter((p) => isNumber(p.train_seconds) && isNumber(p.psnr)));
  const markers = report.curve_markers = await page.evaluate(() => [...document.querySelectorAll('circle.marker')].filter((c) => c.querySelector('title')).length);
  if (markers !== points.length) problems.push(`curves: ${markers} markers with a title, data.js has ${points.length} points`);
  if (markers > 0) {
    // The last marker is painted last, so no other marker covers it.
    await page.locator('circle.marker').last().hover();
    const tip = await page.evaluate(() => { const t = document.getElementById('tooltip'); return t && !t.hidden ? t.textContent : null; });
    if (!tip || !tip.includes('PSNR')) problems.push('curves: hovering a marker shows no tooltip');
  }

  // The zoom clicks may have scrolled a grid sideways: show every grid from its first column.
  await page.evaluate(() => document.querySelectorAll('.scroll').forEach((n) => { n.scrollLeft = 0; }));
  await page.screenshot({ path: outPng, fullPage: true });
} catch (e) {
  problems.push(`check stopped: ${e.message.split('\n')[0]}`);
} finally {
  await browser.close();
}
problems.push(...messages);
const out = { chromium: browser.version, page: join(reportDir, 'index.html'), results_files: results.size, ...report,
  screenshot: resolve(outPng), ok: problems.length === 0, problems };
console.log(JSON.stringify(out));
process.exit(out.ok ? 0 : 1);
