// The weathergs report page: draws window.WEATHERGS_REPORT (set by data.js) with plain DOM and inline
// SVG, so that the report folder opens from the file system with no server, network or library.
// Test hooks (interop/report_check.mjs reads them): data-value on every number, data-variant/view/
// column/metric on per-view metrics, data-table-id and th[data-key] on sortable tables, data-crop on
// zoom tiles inside [data-zoom-row="<variant>/<view>"].
(function () {
  'use strict';

  const SVG_NS = 'http://www.w3.org/2000/svg';
  const THUMB_WIDTH = 200;  // CSS pixels
  const ZOOM_CROP = 48;     // full-resolution pixels on a side of the zoomed square
  const ZOOM_SCALE = 4;
  const METRICS = ['psnr', 'ssim', 'lpips'];
  const DIGITS = { psnr: 2, ssim: 4, lpips: 4 };
  const DASH = '–';
  // Colours by method (seeds of a method share one, with a different dash).
  const PALETTE = ['#1f77b4', '#d62728', '#2ca02c', '#9467bd', '#ff7f0e', '#17becf', '#8c564b', '#e377c2', '#7f7f7f', '#bcbd22'];
  const DASHES = ['', '6 3', '2 3', '8 3 2 3'];

  // --- small helpers ---------------------------------------------------------------------------

  // el('a', {href: 'x'}, child, 'text', [more]): null/undefined/false attributes and children are skipped.
  function el(tag, attrs, ...children) {
    return build(document.createElement(tag), attrs, children);
  }
  function svg(tag, attrs, ...children) {
    return build(document.createElementNS(SVG_NS, tag), attrs, children);
  }
  function build(node, attrs, children) {
    for (const [k, v] of Object.entries(attrs || {}))
      if (v !== undefined && v !== null && v !== false) node.setAttribute(k, String(v));
    for (const c of children.flat(Infinity))
      if (c !== undefined && c !== null && c !== false) node.append(c);
    return node;
  }

  const isNumber = (v) => typeof v === 'number' && Number.isFinite(v);
  // The exact number of data.js, as the checker compares it.
  const dataValue = (v) => (isNumber(v) ? String(v) : 'null');
  const fixed = (v, digits) => (isNumber(v) ? v.toFixed(digits) : DASH);
  // Integers as they are (counts), other numbers with the given decimals.
  const plain = (v, digits) => (isNumber(v) ? (Number.isInteger(v) ? String(v) : v.toFixed(digits)) : DASH);
  const clamp = (v, lo, hi) => Math.min(Math.max(v, lo), hi);
  // data.js holds plain relative paths; each segment is encoded so that '#', '%' or ' ' in a name
  // cannot break a link.
  const url = (path) => String(path).split('/').map(encodeURIComponent).join('/');
  const cssUrl = (path) => `url("${url(path)}")`;

  function checkbox(label, onChange) {
    const input = el('input', { type: 'checkbox' });
    input.addEventListener('change', () => onChange(input.checked));
    return el('label', { class: 'toggle' }, input, ' ', label);
  }

  // One tooltip for the whole page (curve markers).
  const tooltip = document.getElementById('tooltip');
  function showTooltip(text, x, y) {
    tooltip.textContent = text;
    tooltip.hidden = false;
    // Keep it inside the window.
    const w = tooltip.offsetWidth, h = tooltip.offsetHeight;
    tooltip.style.left = `${Math.min(x + 14, window.innerWidth - w - 8)}px`;
    tooltip.style.top = `${Math.min(y + 14, window.innerHeight - h - 8)}px`;
  }
  const hideTooltip = () => { tooltip.hidden = true; };

  // --- sortable tables (leaderboard, cost, runs) -------------------------------------------------

  // {columns, rows} -> <table>: every header sorts (ascending first, then toggles); numeric columns
  // sort by value, others by text; missing values stay last. The best non-reference value of a
  // column with "better" is bold; reference rows are italic and say so, never bold.
  function sortableTable(id, table) {
    const columns = table.columns || [];
    const rows = table.rows || [];
    const cellOf = (row, key) => (row.cells || {})[key] || {};
    const numeric = new Set(columns.filter((c) => rows.some((r) => 'value' in cellOf(r, c.key))).map((c) => c.key));
    const best = {};
    for (const c of columns) {
      if (c.better !== 'higher' && c.better !== 'lower') continue;
      const values = rows.filter((r) => !r.reference).map((r) => cellOf(r, c.key).value).filter(isNumber);
      if (values.length) best[c.key] = c.better === 'higher' ? Math.max(...values) : Math.min(...values);
    }

    const entries = rows.map((row, index) => {
      const tr = el('tr', { class: row.reference ? 'reference' : null }, columns.map((c, k) => {
        const cell = cellOf(row, c.key);
        const hasValue = 'value' in cell;
        const text = cell.text !== undefined ? String(cell.text) : (hasValue ? plain(cell.value, 4) : '');
        const isBest = !row.reference && isNumber(cell.value) && cell.value === best[c.key];
        const classes = [numeric.has(c.key) ? 'num' : '', isBest ? 'best' : ''].filter(Boolean).join(' ');
        return el('td', { 'data-key': c.key, 'data-value': hasValue ? dataValue(cell.value) : null, class: classes || null },
          cell.link ? el('a', { href: url(cell.link) }, text) : text,
          k === 0 && row.reference && !/\(reference\)\s*$/.test(text) ? el('span', { class: 'ref-tag' }, ' (reference)') : null);
      }));
      return { row, index, tr };
    });

    const headers = columns.map((c) => {
      const button = el('button', { type: 'button', title: 'sort by this column' }, c.label ?? c.key, el('span', { class: 'arrow', 'aria-hidden': 'true' }));
      const th = el('th', { 'data-key': c.key, 'aria-sort': 'none', class: numeric.has(c.key) ? 'num' : null }, button);
      th.addEventListener('click', () => sortBy(c.key));
      return th;
    });
    const body = el('tbody', null, entries.map((e) => e.tr));

    let sortKey = null, ascending = true;
    function sortBy(key) {
      ascending = key === sortKey ? !ascending : true;
      sortKey = key;
      const collator = new Intl.Collator(undefined, { numeric: true, sensitivity: 'base' });
      const keyOf = (e) => {
        const cell = cellOf(e.row, key);
        if (numeric.has(key)) return isNumber(cell.value) ? cell.value : null;
        return cell.text !== undefined ? String(cell.text) : null;
      };
      entries.sort((a, b) => {
        const va = keyOf(a), vb = keyOf(b);
        if (va === null || vb === null) return (va === null) - (vb === null) || a.index - b.index;
        const order = numeric.has(key) ? va - vb : collator.compare(va, vb);
        return (ascending ? order : -order) || a.index - b.index;
      });
      body.append(...entries.map((e) => e.tr));
      headers.forEach((th) => th.setAttribute('aria-sort',
        th.dataset.key === key ? (ascending ? 'ascending' : 'descending') : 'none'));
    }

    return el('div', { class: 'scroll' },
      el('table', { class: 'data', 'data-table-id': id }, el('thead', null, el('tr', null, headers)), body));
  }

  // --- sections ----------------------------------------------------------------------------------

  function leaderboardSection(tables) {
    if (!tables.length) return [el('p', { class: 'muted' }, 'No tables in this report.')];
    return tables.map((t) => el('div', { class: 'table-block' },
      el('h3', { id: t.id }, t.title || t.id),
      t.note ? el('p', { class: 'note' }, t.note) : null,
      sortableTable(t.id, t)));
  }

  // One row per test view, one column per image; toggles for difference images and overlays; a
  // click on any image zooms the same crop of every column's full image in a strip under the row.
  function variantSection(v) {
    const columns = v.columns || [];
    const views = v.views || [];
    const fullW = v.width, fullH = v.height;
    const thumbHeight = Math.round(THUMB_WIDTH * fullH / fullW);
    const state = { diff: false, overlays: new Set() };
    const rows = [];  // per view: {view, frames: [{column, cell, img, frame}], zoomTr, zoomCells, zoomLabel, crop}

    const head = el('tr', null, el('th', { class: 'view-name' }, 'view'), columns.map((c) => el('th', null,
      c.run ? el('a', { href: url(c.run), title: 'run folder' }, c.label) : c.label)));
    const body = el('tbody');
    views.forEach((view) => {
      const r = { view, frames: [], crop: null };
      const tr = el('tr', { class: 'view-row' }, el('th', { class: 'view-name', scope: 'row' }, view.name));
      for (const c of columns) {
        const cell = (view.cells || {})[c.id];
        if (!cell) { tr.append(el('td', { class: 'missing' }, 'no image')); r.frames.push({ column: c, cell: null }); continue; }
        const img = el('img', { src: url(cell.thumb), alt: `${c.label}, view ${view.name}`, width: THUMB_WIDTH,
          height: thumbHeight, draggable: 'false' });
        const frame = el('span', { class: 'frame' }, img);
        const link = el('a', { href: url(cell.full), class: 'thumb',
          title: 'click: zoom here in every image of this view; Ctrl+click: open the full image' }, frame);
        // A plain click zooms; modified clicks keep the link's own behaviour (open the full image).
        link.addEventListener('click', (e) => {
          if (e.button !== 0 || e.ctrlKey || e.metaKey || e.shiftKey || e.altKey) return;
          e.preventDefault();
          const box = img.getBoundingClientRect();
          // A keyboard "click" has no position: zoom at the centre.
          const fx = e.detail === 0 ? fullW / 2 : (e.clientX - box.left) * fullW / box.width;
          const fy = e.detail === 0 ? fullH / 2 : (e.clientY - box.top) * fullH / box.height;
          zoom(r, fx, fy);
        });
        const metrics = cell.metrics ? el('div', { class: 'metrics' }, METRICS.map((m) => el('span', null,
          `${m.toUpperCase()} `,
          el('span', { 'data-variant': v.name, 'data-view': view.name, 'data-column': c.id, 'data-metric': m,
            'data-value': dataValue(cell.metrics[m]) }, fixed(cell.metrics[m], DIGITS[m]))))) : null;
        tr.append(el('td', null, link, metrics));
        r.frames.push({ column: c, cell, img, frame });
      }
      r.zoomLabel = el('div', { class: 'zoom-label' });
      const close = el('button', { type: 'button', class: 'close' }, 'close');
      close.addEventListener('click', () => { r.crop = null; r.zoomTr.hidden = true; drawCropBoxes(r); });
      r.zoomCells = columns.map(() => el('td'));
      r.zoomTr = el('tr', { class: 'zoom-row', 'data-zoom-row': `${v.name}/${view.name}`, hidden: '' },
        el('th', { class: 'view-name' }, `zoom ×${ZOOM_SCALE}`, r.zoomLabel, close), r.zoomCells);
      body.append(tr, r.zoomTr);
      rows.push(r);
    });

    function zoom(r, fx, fy) {
      const size = Math.min(ZOOM_CROP, fullW, fullH);
      const x = clamp(Math.round(fx - size / 2), 0, fullW - size);
      const y = clamp(Math.round(fy - size / 2), 0, fullH - size);
      r.crop = { x, y, w: size, h: size };
      r.zoomTr.hidden = false;
      drawZoom(r);
      drawCropBoxes(r);
    }

    // Every tile shows the crop of its column's full image as a scaled, pixelated background; the
    // checked overlays are further layers of the same geometry.
    function drawZoom(r) {
      if (!r.crop) return;
      const { x, y, w, h } = r.crop;
      r.zoomLabel.textContent = `x ${x}–${x + w}, y ${y}–${y + h}`;
      const place = (node, path) => {
        node.style.backgroundImage = cssUrl(path);
        node.style.backgroundSize = `${fullW * ZOOM_SCALE}px ${fullH * ZOOM_SCALE}px`;
        node.style.backgroundPosition = `${-x * ZOOM_SCALE}px ${-y * ZOOM_SCALE}px`;
        return node;
      };
      r.frames.forEach((f, k) => {
        const tile = el('div', { class: 'zoom-tile', 'data-crop': `${x},${y},${w},${h}`, 'data-column': f.column.id,
          title: `${f.column.label}: x ${x}–${x + w}, y ${y}–${y + h} of the full image` });
        tile.style.width = `${w * ZOOM_SCALE}px`;
        tile.style.height = `${h * ZOOM_SCALE}px`;
        if (f.cell && f.cell.full) place(tile, f.cell.full);
        for (const id of state.overlays) {
          const path = (r.view.overlays || {})[id];
          if (path) tile.append(place(el('div', { class: 'zoom-overlay' }), path));
        }
        r.zoomCells[k].replaceChildren(tile);
      });
    }

    // A box on every thumbnail of the row marks the zoomed crop.
    function drawCropBoxes(r) {
      for (const f of r.frames) {
        if (!f.frame) continue;
        let box = f.frame.querySelector('.crop-box');
        if (!r.crop) { if (box) box.remove(); continue; }
        if (!box) box = f.frame.appendChild(el('span', { class: 'crop-box' }));
        box.style.left = `${100 * r.crop.x / fullW}%`;
        box.style.top = `${100 * r.crop.y / fullH}%`;
        box.style.width = `${100 * r.crop.w / fullW}%`;
        box.style.height = `${100 * r.crop.h / fullH}%`;
      }
    }

    // Thumbnails or difference images, and the overlays: their <img> are made on first use, so that
    // an unchecked overlay costs nothing.
    function update() {
      for (const r of rows) {
        for (const f of r.frames) {
          if (!f.img) continue;
          const src = url(state.diff && f.cell.diff ? f.cell.diff : f.cell.thumb);
          if (f.img.getAttribute('src') !== src) f.img.setAttribute('src', src);
          for (const o of v.overlays || []) {
            const path = (r.view.overlays || {})[o.id];
            let layer = [...f.frame.querySelectorAll('img.overlay')].find((n) => n.dataset.overlay === o.id);
            if (!layer && path && state.overlays.has(o.id)) {
              layer = el('img', { class: 'overlay', src: url(path), alt: '', 'data-overlay': o.id });
              f.frame.insertBefore(layer, f.frame.querySelector('.crop-box'));
            }
            if (layer) layer.hidden = !state.overlays.has(o.id);
          }
        }
        drawZoom(r);
      }
    }

    const controls = el('div', { class: 'controls' },
      checkbox('difference to truth', (on) => { state.diff = on; update(); }),
      (v.overlays || []).map((o) => checkbox(o.label, (on) => {
        if (on) state.overlays.add(o.id); else state.overlays.delete(o.id);
        update();
      })));
    const size = isNumber(fullW) && isNumber(fullH) ? `, ${fullW}×${fullH}` : '';
    return [
      el('p', { class: 'muted' }, `scene ${v.scene}, weather ${v.weather}${size}; ${views.length} test view(s). `,
        'Click an image to zoom the same spot of every image of its view.'),
      (v.without_renders || []).length ? el('p', { class: 'muted', 'data-without-renders': v.name },
        `Restored from the results archive, which keeps no renders (their numbers are in the tables): ${v.without_renders.join(', ')}.`) : null,
      controls,
      el('div', { class: 'scroll grid-scroll' }, el('table', { class: 'grid', 'data-variant': v.name }, el('thead', null, head), body)),
    ];
  }

  // Tick positions at 1, 2 or 5 times a power of ten; the domain is widened to whole ticks.
  function ticks(lo, hi, count) {
    if (!(hi > lo)) { lo -= 1; hi += 1; }
    const raw = (hi - lo) / count;
    const power = 10 ** Math.floor(Math.log10(raw));
    const step = [1, 2, 5, 10].map((m) => m * power).find((s) => s >= raw);
    const start = Math.floor(lo / step) * step, end = Math.ceil(hi / step) * step;
    const decimals = Math.max(0, -Math.floor(Math.log10(step)));
    const list = [];
    for (let t = start; t <= end + step / 2; t += step) list.push(Number(t.toFixed(decimals)));
    return { lo: start, hi: end, list, decimals };
  }

  // PSNR over training time, one polyline and its markers per (method, seed).
  function chart(series) {
    const W = 680, H = 320, m = { left: 56, right: 16, top: 12, bottom: 44 };
    const usable = (p) => isNumber(p.train_seconds) && isNumber(p.psnr);
    const all = series.flatMap((s) => (s.points || []).filter(usable));
    const xt = ticks(Math.min(0, ...all.map((p) => p.train_seconds)), Math.max(...all.map((p) => p.train_seconds)), 6);
    const yt = ticks(Math.min(...all.map((p) => p.psnr)), Math.max(...all.map((p) => p.psnr)), 5);
    const X = (t) => m.left + (t - xt.lo) / (xt.hi - xt.lo) * (W - m.left - m.right);
    const Y = (p) => H - m.bottom - (p - yt.lo) / (yt.hi - yt.lo) * (H - m.top - m.bottom);

    const methods = [...new Set(series.map((s) => s.method))];
    const style = (s) => {
      const seeds = [...new Set(series.filter((o) => o.method === s.method).map((o) => o.seed))];
      return { color: PALETTE[methods.indexOf(s.method) % PALETTE.length],
        dash: DASHES[seeds.indexOf(s.seed) % DASHES.length] || null };
    };
    const name = (s) => `${s.method} (seed ${s.seed})`;

    const grid = [
      xt.list.map((t) => svg('g', { class: 'tick' },
        svg('line', { x1: X(t), x2: X(t), y1: m.top, y2: H - m.bottom }),
        svg('text', { x: X(t), y: H - m.bottom + 16, 'text-anchor': 'middle' }, t.toFixed(xt.decimals)))),
      yt.list.map((t) => svg('g', { class: 'tick' },
        svg('line', { x1: m.left, x2: W - m.right, y1: Y(t), y2: Y(t) }),
        svg('text', { x: m.left - 6, y: Y(t) + 4, 'text-anchor': 'end' }, t.toFixed(yt.decimals)))),
      svg('text', { class: 'axis-label', x: (m.left + W - m.right) / 2, y: H - 6, 'text-anchor': 'middle' }, 'training time (s)'),
      svg('text', { class: 'axis-label', x: 14, y: (m.top + H - m.bottom) / 2, 'text-anchor': 'middle',
        transform: `rotate(-90 14 ${(m.top + H - m.bottom) / 2})` }, 'PSNR (dB)'),
    ];
    const lines = series.map((s) => {
      const { color, dash } = style(s);
      const pts = (s.points || []).filter(usable);
      const markers = pts.map((p) => {
        const text = [name(s), `iteration ${plain(p.iteration, 0)}`, `training ${fixed(p.train_seconds, 2)} s`,
          `PSNR ${fixed(p.psnr, 2)}`, `SSIM ${fixed(p.ssim, 4)}`, `LPIPS ${fixed(p.lpips, 4)}`,
          `Gaussians ${plain(p.num_gaussians, 0)}`].join('\n');
        const c = svg('circle', { class: 'marker', cx: X(p.train_seconds), cy: Y(p.psnr), r: 3.5, fill: color, tabindex: 0 },
          svg('title', null, text));
        c.addEventListener('mouseenter', (e) => showTooltip(text, e.clientX, e.clientY));
        c.addEventListener('mouseleave', hideTooltip);
        c.addEventListener('focus', () => { const b = c.getBoundingClientRect(); showTooltip(text, b.right, b.bottom); });
        c.addEventListener('blur', hideTooltip);
        return c;
      });
      return svg('g', { class: 'series' },
        svg('polyline', { points: pts.map((p) => `${X(p.train_seconds)},${Y(p.psnr)}`).join(' '), stroke: color,
          'stroke-dasharray': dash, fill: 'none' }),
        markers);
    });
    const legend = el('ul', { class: 'legend' }, series.map((s) => {
      const { color, dash } = style(s);
      return el('li', null, svg('svg', { width: 28, height: 10, 'aria-hidden': 'true' },
        svg('line', { x1: 1, x2: 27, y1: 5, y2: 5, stroke: color, 'stroke-width': 2, 'stroke-dasharray': dash })), ' ', name(s));
    }));
    return [svg('svg', { class: 'chart', viewBox: `0 0 ${W} ${H}`, width: W, height: H, role: 'img',
      'aria-label': 'PSNR against training time' }, grid, lines), legend];
  }

  function curvesSection(curves, variants) {
    // Variants in report order, then any that only the curves name.
    const names = [...new Set([...variants.map((v) => v.name), ...curves.map((c) => c.variant)])];
    const figures = names.map((name) => {
      const series = curves.filter((c) => c.variant === name && (c.points || []).some((p) => isNumber(p.train_seconds) && isNumber(p.psnr)));
      if (!series.length) return null;
      return el('figure', { class: 'curve', 'data-variant': name }, el('figcaption', null, `${name}: test PSNR during training`), chart(series));
    }).filter(Boolean);
    return figures.length ? figures : [el('p', { class: 'muted' }, 'No training curves in this report.')];
  }

  function costSection(cost, runs) {
    const numberCell = (v, digits, format = plain) => ({ text: format(v, digits), value: isNumber(v) ? v : null });
    const runTable = {
      columns: [{ key: 'variant', label: 'variant' }, { key: 'method', label: 'method' }, { key: 'seed', label: 'seed' },
        { key: 'train_seconds', label: 'training (s)' }, { key: 'peak_rss_mb', label: 'peak memory (MiB)' },
        { key: 'num_gaussians', label: 'Gaussians' }, { key: 'dataset_identity', label: 'dataset identity' },
        { key: 'recipe', label: 'recipe' }, { key: 'path', label: 'run folder' }],
      rows: runs.map((r) => ({ reference: false, cells: {
        variant: { text: r.variant }, method: { text: r.method }, seed: numberCell(r.seed, 0),
        train_seconds: numberCell(r.train_seconds, 1, fixed), peak_rss_mb: numberCell(r.peak_rss_mb, 0),
        num_gaussians: numberCell(r.num_gaussians, 0),
        dataset_identity: { text: (r.dataset_identity || DASH) + (r.other_data ? ' \u2020' : '') },
        recipe: { text: (r.recipe || DASH) + (r.other_recipe ? ' \u2021' : '') + (r.archived ? ' (archived)' : '') },
        path: { text: r.path, link: r.path } } })),
    };
    return [
      cost && (cost.rows || []).length ? sortableTable('cost', cost) : el('p', { class: 'muted' }, 'No cost table in this report.'),
      el('h3', null, 'Runs'),
      runs.length ? sortableTable('runs', runTable) : el('p', { class: 'muted' }, 'No runs in this report.'),
    ];
  }

  // The results archive's converged runs of this report's variants: the same tables, apart from the
  // report's own (a table holds one recipe), or a plain sentence when the archive holds none.
  function convergedSection(c) {
    const lines = (c.lines || []).map((line) => el('p', { class: 'note' }, line));
    const where = el('p', { class: 'muted' }, 'Archive: ', c.link ? el('a', { href: url(c.link) }, el('code', null, c.path)) : el('code', null, c.path));
    if (!(c.tables || []).length)
      return [where, el('p', { class: 'empty-archive', 'data-converged-empty': '' }, c.message || 'The archive holds no run of these variants.'), lines];
    return [
      where, lines,
      leaderboardSection(c.tables),
      el('h3', null, 'Cost'),
      c.cost && (c.cost.rows || []).length ? sortableTable('converged-cost', c.cost) : el('p', { class: 'muted' }, 'No cost table.'),
    ];
  }

  function provenanceSection(p) {
    // One row per entry: its name, then one column per [key, header].
    const hashes = (list, columns) => (list && list.length
      ? el('table', { class: 'data hashes' },
        el('thead', null, el('tr', null, el('th', null, 'name'), columns.map(([, header]) => el('th', null, header)))),
        el('tbody', null, list.map((w) => el('tr', null, el('td', null, w.name),
          columns.map(([key]) => el('td', null, el('code', null, w[key] || DASH)))))))
      : el('p', { class: 'muted' }, 'none'));
    return [
      el('dl', { class: 'prov' },
        el('dt', null, 'commit'), el('dd', null, el('code', null, p.commit || DASH)),
        el('dt', null, 'protocol'), el('dd', null, el('code', null, p.protocol || DASH)),
        el('dt', null, 'command'), el('dd', null, el('code', null, p.command || DASH))),
      el('h3', null, 'Weights'), hashes(p.weights, [['sha256', 'sha256']]),
      el('h3', null, 'Datasets'), hashes(p.datasets, [['dataset_identity', 'dataset identity (sha256)'],
        ['ground_truth_sha256', 'ground-truth sha256']]),
    ];
  }

  // --- the page ----------------------------------------------------------------------------------

  const data = window.WEATHERGS_REPORT;
  const main = document.getElementById('report');
  if (!data || data.format !== 'weathergs-report') {
    main.append(el('p', { class: 'problem' }, 'data.js is missing or does not hold a weathergs report.'));
    return;
  }
  if (data.version !== 1)
    main.append(el('p', { class: 'problem' }, `data.js is version ${data.version}; this page reads version 1.`));
  if (data.title) {
    document.title = data.title;
    document.getElementById('title').textContent = data.title;
  }

  // What this suite is (e.g. a smoke run, not converged), above everything.
  if (data.note)
    main.append(el('p', { class: 'run-note', id: 'run-note' }, data.note,
      data.converged ? [' ', el('a', { href: '#converged' }, 'The converged tables: Converged (archive).')] : null));

  const variants = data.variants || [];
  const sections = [
    ['leaderboard', 'Leaderboard', () => leaderboardSection(data.tables || [])],
    data.converged ? ['converged', 'Converged (archive)', () => convergedSection(data.converged)] : null,
    ...variants.map((v) => [`variant-${v.name}`, v.name, () => variantSection(v)]),
    ['curves', 'Curves', () => curvesSection(data.curves || [], variants)],
    ['cost', 'Cost', () => costSection(data.cost, data.runs || [])],
    ['provenance', 'Provenance', () => provenanceSection(data.provenance || {})],
  ];
  const nav = document.getElementById('nav');
  for (const [id, label, draw] of sections.filter(Boolean)) {
    nav.append(el('a', { href: `#${encodeURIComponent(id)}` }, label));
    main.append(el('section', { id }, el('h2', null, label), draw()));
  }
})();
