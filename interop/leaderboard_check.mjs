// The HTML leaderboard (`weathergs leaderboard ... --format html`) opened in headless Chromium: a
// full-page screenshot, and every number of every table, read from the DOM, equals the metric of the
// results files it comes from (rounded as printed); every results file appears in a table.
// Usage: node leaderboard_check.mjs LEADERBOARD.html OUT_DIR RESULTS.json...
import { readFileSync, mkdirSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';
import { launch } from './browser.mjs';

const [html, out, ...files] = process.argv.slice(2);
if (!html || !out || files.length === 0) { console.error('usage: leaderboard_check.mjs HTML OUT RESULTS...'); process.exit(2); }
mkdirSync(out, { recursive: true });
const results = files.map((f) => ({ file: f, ...JSON.parse(readFileSync(f, 'utf8')) }));

const browser = await launch();
let tables;
const screenshot = join(out, 'leaderboard.png');
try {
  const page = await browser.context.newPage();
  await page.goto(pathToFileURL(resolve(html)).href);
  await page.screenshot({ path: screenshot, fullPage: true });
  // Each table: the weather from the <h2> before it, the scene of each column (the group header,
  // repeated over its colspan), the metric of each column, and the rows as text.
  tables = await page.evaluate(() => [...document.querySelectorAll('table')].map((t) => {
    let h = t.previousElementSibling;
    while (h && h.tagName !== 'H2') h = h.previousElementSibling;
    const [groupRow, metricRow] = t.querySelectorAll('thead tr');
    const scenes = [];
    for (const th of groupRow.querySelectorAll('th.group'))
      for (let k = 0; k < Number(th.getAttribute('colspan') || 1); ++k) scenes.push(th.textContent.trim());
    const metrics = [...metricRow.querySelectorAll('th')].map((th) => th.textContent.replace(/[^A-Za-z]/g, '').toLowerCase());
    const rows = [...t.querySelectorAll('tbody tr')].map((tr) => [...tr.querySelectorAll('td')].map((td) => td.textContent.trim()));
    return { title: h ? h.textContent.trim() : '', scenes, metrics, rows };
  }));
} finally {
  await browser.close();
}

const problems = [];
let checked = 0;
const used = new Set();
for (const t of tables) {
  const weather = t.title.replace(/^Weather:\s*/i, '').toLowerCase();
  for (const row of t.rows) {
    const method = row[0];
    row.slice(1).forEach((text, c) => {
      const scene = t.scenes[c], metric = t.metrics[c];
      const sources = results.filter((r) => r.method === method && r.weather.toLowerCase() === weather &&
        (scene === 'Average' || r.scene === scene));
      if (text === '' || text === '-' || text === '—') return;  // a cell without a value
      if (sources.length === 0) { problems.push(`${t.title} / ${method} / ${scene} ${metric}: '${text}' but no results file`); return; }
      const expected = sources.reduce((s, r) => s + r.metrics[metric], 0) / sources.length;
      const decimals = (text.split('.')[1] || '').length;
      const shown = Number(text);
      if (!(Math.abs(shown - expected) <= 0.5 * 10 ** -decimals + 1e-9))
        problems.push(`${t.title} / ${method} / ${scene} ${metric}: page ${text}, results ${expected}`);
      if (scene !== 'Average') sources.forEach((r) => used.add(r.file));
      ++checked;
    });
  }
}
for (const r of results) if (!used.has(r.file)) problems.push(`${r.file}: not in any table`);
const report = { chromium: browser.version, tables: tables.length, cells_checked: checked, results_files: files.length,
  screenshot, ok: problems.length === 0 && checked > 0, problems };
console.log(JSON.stringify(report));
process.exit(report.ok ? 0 : 1);
