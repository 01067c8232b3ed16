#!/usr/bin/env node
// Checks a vrpt HTML report (`--report`) in headless Chromium, as a person would use it.
//
//   node tests/browser/check_report.mjs REPORT.html EXPECT.json SCREENSHOT_DIR
//
// Node 20, no npm packages: drives Debian's chromedriver (/usr/bin/chromedriver, or
// $CHROMEDRIVER) over the W3C WebDriver HTTP protocol with the global fetch; Chromium is
// $CHROMIUM or /usr/bin/chromium. Exit 0 when every check passes, 1 with one line per failed
// check (or a run that could not be made, e.g. no browser), 2 on bad arguments.
//
// EXPECT.json (written by whoever made the report, from the run's own results):
// {
//   "metrics": [{"table": 0, "row": "mis", "column": "mse", "value": 1.23e-4}, ...],
//       table index in the payload, the row's row_key value, the column key, the exact number;
//   "probe": [[x, y], ...],
//       image pixels (x right, y down) of the image shown first (the first non-reference image
//       of the first group) whose every channel stays unsaturated (8-bit value < 255) at
//       exposure +1 and is not black at exposure 0; best with linear values in ~[0.05, 0.45];
//       they must differ between the A and B images below;
//   "hover": {"x": 10, "y": 20,
//             "values": {"<image name>": [r, g, b], ...},    linear RGB of that pixel (f32 or f64),
//             "stderr": {"<image name>": [r, g, b], ...}},   its standard error of the mean;
//       names are of images in the first group (or the reference);
//   "ab": {"a": "<image name>", "b": "<image name>"},          the two images of the A/B check
//   "summary": {"key": "mse", "order": ["<strategy>", ...],     (compare only) the ranking the page
//               "values": {"<strategy>": 1.2e-4, ...}}          opens on, best first, and each value
// }
//
// The page contract checked here (src/analysis/report/report.html): canvas#canvas holds the view at one
// canvas pixel per image pixel; buttons[data-mode] switch the view; #exposure is the exposure
// range input; #ab, #ab-a, #ab-b, #divide are the A/B controls (image x < divide shows A);
// #cbar-min/#cbar-max are the colour bar's labels (data-value exact); #inspector holds
// [data-image][data-kind=value|stderr][data-rgb]; table[data-table=i] cells carry data-row,
// data-col, data-value; #summary (compare) holds table#summary-table (rows tr[data-row] best
// first, cells data-col/data-value) and canvas#summary-best / canvas#summary-reference (one
// canvas pixel per image pixel, exposure 0). The page sets window.__vrptReady and records errors
// in __vrptErrors.
import { spawn } from 'node:child_process';
import { readFileSync, writeFileSync, mkdirSync } from 'node:fs';
import { createServer } from 'node:net';
import { resolve, join } from 'node:path';
import { pathToFileURL } from 'node:url';
import { inflateSync } from 'node:zlib';

const [reportPath, expectPath, shotDir] = process.argv.slice(2);
if (!shotDir) {
  console.error('usage: node check_report.mjs REPORT.html EXPECT.json SCREENSHOT_DIR');
  process.exit(2);
}
const EXPECT = JSON.parse(readFileSync(expectPath, 'utf8'));
const html = readFileSync(reportPath, 'utf8');
mkdirSync(shotDir, { recursive: true });
const started = Date.now();

// ---- the payload, decoded here independently of the page ---------------------------------
const m = html.match(/<script type="application\/json" id="vrpt-data">([\s\S]*?)<\/script>/);
if (!m) { console.error('FAIL: the report has no vrpt-data tag'); process.exit(1); }
const DATA = JSON.parse(m[1]);
const W = DATA.width, H = DATA.height;
function half(h) {
  const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 31, f = h & 1023;
  if (e === 0) return s * f * 2 ** -24;
  if (e === 31) return f ? NaN : s * Infinity;
  return s * (1 + f / 1024) * 2 ** (e - 15);
}
/** base64 → zlib → n low bytes then n high bytes of binary16 values (report.rs, encode_halves). */
const decode = (b64) => {
  const b = inflateSync(Buffer.from(b64, 'base64')), n = b.length / 2, out = new Float64Array(n);
  for (let i = 0; i < n; i++) out[i] = half(b[i] | (b[n + i] << 8));
  return out;
};
DATA.images = DATA.images || [];
const IMG = DATA.images.map((im) => decode(im.rgb));
const REF = DATA.images.findIndex((im) => im.reference);
const oetf = (v) => (v <= 0.0031308 ? 12.92 * v : 1.055 * v ** (1 / 2.4) - 0.055);
const eotf = (s) => (s <= 0.04045 ? s / 12.92 : ((s + 0.055) / 1.055) ** 2.4);
/** The 8-bit sRGB value of linear v at exposure e (what the page must draw). */
const tone = (v, e) => (Number.isNaN(v) ? 0 : Math.round(255 * oetf(Math.min(1, Math.max(0, v * 2 ** e)))));
const byName = (name) => {
  const firstGroup = DATA.images.find((im) => !im.reference)?.group ?? '';
  const i = DATA.images.findIndex((im) => im.name === name && (im.reference || im.group === firstGroup));
  return i >= 0 ? i : DATA.images.findIndex((im) => im.name === name);
};

// ---- checks ------------------------------------------------------------------------------
const failures = [];
let passed = 0;
function check(ok, msg) {
  if (ok) passed++;
  else { failures.push(msg); console.log('FAIL: ' + msg); }
  return ok;
}
const relClose = (a, b, rel, abs = 0) => Math.abs(a - b) <= rel * Math.abs(b) + abs;
const parseShown = (s) => Number(s.trim().replace('−', '-'));

// ---- WebDriver over HTTP -----------------------------------------------------------------
const ELEM = 'element-6066-11e4-a52e-4f735466cecf';
let base, session, driver;
async function wd(method, path, body) {
  const res = await fetch(base + path, {
    method, headers: { 'content-type': 'application/json' },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  const json = await res.json();
  if (json.value && json.value.error) throw new Error(`${method} ${path}: ${json.value.error}: ${json.value.message}`);
  return json.value;
}
const s = (p) => `/session/${session}${p}`;
const js = (script, ...args) => wd('POST', s('/execute/sync'), { script, args });
const find = async (css) => {
  const v = await wd('POST', s('/element'), { using: 'css selector', value: css });
  if (!v || !v[ELEM]) throw new Error('no element ' + css + ': ' + JSON.stringify(v));
  return v;
};
const click = async (css) => wd('POST', s(`/element/${(await find(css))[ELEM]}/click`), {});
const actions = (list) => wd('POST', s('/actions'), { actions: list }).then(() => wd('DELETE', s('/actions')));
const press = (key) => actions([{ type: 'key', id: 'kbd', actions: [{ type: 'keyDown', value: key }, { type: 'keyUp', value: key }] }]);
let shotNo = 0;
/** A screenshot of the viewer (page scrolled to the top), or of the element `css` scrolled into view. */
async function screenshot(name, css) {
  await js(css ? `document.querySelector(arguments[0]).scrollIntoView()` : 'window.scrollTo(0, 0)', css);
  const png = await wd('GET', s('/screenshot'));
  const file = join(shotDir, `${String(++shotNo).padStart(2, '0')}-${name}.png`);
  writeFileSync(file, Buffer.from(png, 'base64'));
  console.log('screenshot ' + file);
}
/** Canvas RGB at image pixels [[x, y], ...]. */
const canvasAt = (pts) => js(`const c = document.getElementById('canvas').getContext('2d');
  return arguments[0].map(([x, y]) => Array.from(c.getImageData(x, y, 1, 1).data.slice(0, 3)));`, pts);
/** The whole canvas as RGBA bytes. */
const canvasAll = async () => Buffer.from(await js(`const d = document.getElementById('canvas').getContext('2d').getImageData(0, 0, ${W}, ${H}).data;
  let s = ''; for (let i = 0; i < d.length; i += 8192) s += String.fromCharCode.apply(null, d.subarray(i, i + 8192)); return btoa(s);`), 'base64');
/** Set an input's value and fire its input and change events, as a person moving it would. */
const setInput = (id, value) => js(`const el = document.getElementById(arguments[0]); el.value = arguments[1];
  el.dispatchEvent(new Event('input', {bubbles: true})); el.dispatchEvent(new Event('change', {bubbles: true}));`, id, String(value));
const canvasHash = () => js(`const d = document.getElementById('canvas').getContext('2d').getImageData(0, 0, ${W}, ${H}).data;
  let h = 2166136261; for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 16777619); return h >>> 0;`);
/** Viewport coordinates of the centre of image pixel (x, y). */
const pixelCentre = (x, y) => js(`const r = document.getElementById('canvas').getBoundingClientRect();
  return [Math.round(r.left + (arguments[0] + 0.5) * r.width / ${W}), Math.round(r.top + (arguments[1] + 0.5) * r.height / ${H})];`, x, y);
/** Zoom in until an image pixel is at least 2 screen pixels wide, so a pointer can hit one pixel. */
async function zoomForPointer() {
  for (let k = 0; k < 8 && (await js(`return document.getElementById('canvas').getBoundingClientRect().width / ${W}`)) < 2; k++) await click('#zoom-in');
}
/** Scroll the view so image pixel (x, y) is in the middle; the image x range then in view. */
const centreOn = (x, y) => js(`const v = document.getElementById('viewport'), c = document.getElementById('canvas');
  const z = c.getBoundingClientRect().width / ${W};
  v.scrollLeft = (arguments[0] + 0.5) * z - v.clientWidth / 2; v.scrollTop = (arguments[1] + 0.5) * z - v.clientHeight / 2;
  v.scrollIntoView({block: 'nearest'});
  const r = c.getBoundingClientRect(), vr = v.getBoundingClientRect();
  return [Math.max(0, (vr.left - r.left) / z), Math.min(${W}, (vr.right - r.left) / z)];`, x, y);
const mouse = (steps) => actions([{ type: 'pointer', id: 'mouse', parameters: { pointerType: 'mouse' }, actions: steps }]);

async function freePort() {
  return new Promise((ok, bad) => {
    const srv = createServer().listen(0, '127.0.0.1', () => { const p = srv.address().port; srv.close(() => ok(p)); });
    srv.on('error', bad);
  });
}

async function start() {
  const port = await freePort();
  base = `http://127.0.0.1:${port}`;
  driver = spawn(process.env.CHROMEDRIVER || '/usr/bin/chromedriver', [`--port=${port}`], { stdio: 'ignore' });
  driver.on('error', (e) => { console.error('cannot start chromedriver: ' + e.message); process.exit(2); });
  for (let t = 0; ; t++) {
    try { if ((await wd('GET', '/status')).ready) break; } catch { /* not listening yet */ }
    if (t > 200) throw new Error('chromedriver did not get ready in 20 s');
    await new Promise((r) => setTimeout(r, 100));
  }
  const caps = {
    browserName: 'chrome',
    'goog:loggingPrefs': { browser: 'ALL' },
    'goog:chromeOptions': {
      binary: process.env.CHROMIUM || '/usr/bin/chromium',
      args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage', '--disable-background-networking',
        '--disable-extensions', '--no-first-run', '--window-size=1400,1000'],
    },
  };
  session = (await wd('POST', '/session', { capabilities: { alwaysMatch: caps } })).sessionId;
}

// ---- the checks, in the order a person would go -----------------------------------------
async function run() {
  await wd('POST', s('/url'), { url: pathToFileURL(resolve(reportPath)).href });
  for (let t = 0; !(await js('return window.__vrptReady === true')); t++) {
    if (t > 100) throw new Error('the page never set window.__vrptReady');
    await new Promise((r) => setTimeout(r, 100));
  }
  await screenshot('initial');
  if (!check(IMG.length > 0, 'the report payload holds no images')) return pageErrors();

  // the summary (compare): the page opens on it, above the viewer and in the first screenful;
  // the ranking's order and values; the best image and the reference drawn from the data; the
  // viewer starts on the best image
  if (EXPECT.summary) {
    const sum = EXPECT.summary, best = byName(sum.order[0]);
    const box = await js(`const s = document.getElementById('summary'), v = document.getElementById('viewer');
      return {hidden: s.hidden, top: s.getBoundingClientRect().top, viewer: v.getBoundingClientRect().top, h: window.innerHeight};`);
    check(!box.hidden && box.top < box.viewer && box.top < box.h / 2,
      `the summary is not what the page opens on: ${JSON.stringify(box)}`);
    const rows = await js(`return [...document.querySelectorAll('#summary-table tbody tr')].map((tr) => ({row: tr.dataset.row,
      value: [...tr.cells].find((c) => c.dataset.col === arguments[0])?.dataset.value ?? null}));`, sum.key);
    check(JSON.stringify(rows.map((r) => r.row)) === JSON.stringify(sum.order),
      `summary ranking ${rows.map((r) => r.row).join(', ')}, expected ${sum.order.join(', ')}`);
    for (const r of rows) {
      check(r.value !== null && relClose(Number(r.value), sum.values[r.row], 1e-9),
        `summary ${sum.key} of ${r.row}: ${r.value}, expected ${sum.values[r.row]}`);
    }
    for (const [id, i] of [['summary-best', best], ['summary-reference', REF]]) {
      const got = await js(`const c = document.getElementById(arguments[0]);
        return {index: c.dataset.index, w: c.width, h: c.height, px: Array.from(c.getContext('2d').getImageData(0, 0, c.width, c.height).data)};`, id);
      if (!check(Number(got.index) === i && got.w === W && got.h === H, `#${id} shows image ${got.index} (${got.w}x${got.h}), not ${i}`)) continue;
      let bad = 0;
      for (let p = 0; p < W * H; p++) for (let c = 0; c < 3; c++) if (Math.abs(got.px[4 * p + c] - tone(IMG[i][3 * p + c], 0)) > 1) bad++;
      check(bad === 0, `#${id}: ${bad} pixel channels differ from ${DATA.images[i].name}'s data`);
    }
    check(Number(await js(`return document.getElementById('canvas').dataset.index`)) === best,
      `the viewer does not open on the best strategy, ${sum.order[0]}`);
    await screenshot('summary', '#summary');
  }

  // metrics: exact data-value, shown to 4 significant digits
  for (const e of EXPECT.metrics || []) {
    const where = `table ${e.table} row ${JSON.stringify(e.row)} column ${e.column}`;
    const cell = await js(`const t = document.querySelector('table[data-table="' + arguments[0] + '"]');
      const td = t && [...t.querySelectorAll('td')].find((c) => c.dataset.row === arguments[1] && c.dataset.col === arguments[2]);
      return td ? {value: td.dataset.value ?? null, text: td.textContent} : null;`, e.table, String(e.row), e.column);
    if (!check(cell, `metric cell not found: ${where}`)) continue;
    check(cell.value !== null && relClose(Number(cell.value), e.value, 1e-9), `metric ${where}: data-value ${cell.value}, expected ${e.value}`);
    check(relClose(parseShown(cell.text), e.value, 0.5e-3, 1e-300), `metric ${where}: shows "${cell.text}", expected ${e.value} to 4 digits`);
  }

  // sorting: every numeric column with two or more numbers (at most 40 columns in all)
  const sortable = (DATA.tables || []).flatMap((t, ti) => t.columns
    .filter((c) => c.numeric && t.rows.filter((r) => typeof r[c.key] === 'number').length > 1).map((col) => [ti, col])).slice(0, 40);
  for (const [ti, col] of sortable) {
    const order = () => js(`return [...document.querySelectorAll('table[data-table="${ti}"] tbody tr')].map((tr) =>
      [...tr.cells].find((c) => c.dataset.col === arguments[0]).dataset.value ?? null);`, col.key);
    for (const dir of [1, -1]) {
      await click(`table[data-table="${ti}"] th[data-col="${col.key}"]`);
      const got = await order(), nums = got.filter((v) => v !== null).map(Number);
      const sorted = [...nums].sort((a, b) => dir * (a - b));
      check(nums.join() === sorted.join() && got.slice(nums.length).every((v) => v === null),
        `table ${ti} sorted by ${col.key} ${dir > 0 ? 'ascending' : 'descending'}: got ${got.join(', ')}`);
    }
  }

  // exposure: +1 stop doubles the linear value read back through sRGB. Tolerance from 8-bit
  // quantisation, per pixel and channel: byte b stands for any linear value in
  // [eotf((b-0.5)/255), eotf((b+0.5)/255)], so the ratio of the two readings can be anything in
  // [lo1/hi0, hi1/lo0]; 2 must lie in that interval.
  const probes = EXPECT.probe || [];
  check(probes.length > 0, 'EXPECT.probe is empty');
  const shown = Number(await js(`return document.getElementById('canvas').dataset.index`));
  await js('document.activeElement && document.activeElement.blur()');
  const at0 = await canvasAt(probes);
  await press('e');
  check(Number(await js(`return document.getElementById('exposure').value`)) === 1, 'key e did not set the exposure slider to +1');
  const at1 = await canvasAt(probes);
  await screenshot('exposure-plus-1');
  const lin = (b) => [eotf(Math.max(b - 0.5, 0) / 255), eotf(Math.min(b + 0.5, 255) / 255)];
  probes.forEach(([x, y], k) => {
    for (let c = 0; c < 3; c++) {
      const v = IMG[shown][3 * (y * W + x) + c];
      check(Math.abs(at0[k][c] - tone(v, 0)) <= 1 && Math.abs(at1[k][c] - tone(v, 1)) <= 1,
        `pixel (${x},${y}) channel ${c}: drew ${at0[k][c]}/${at1[k][c]} at exposure 0/+1, expected ${tone(v, 0)}/${tone(v, 1)} from the data`);
      if (!check(at0[k][c] > 0 && at1[k][c] < 255, `probe (${x},${y}) channel ${c} is black or saturated (${at0[k][c]}, ${at1[k][c]})`)) continue;
      const [lo0, hi0] = lin(at0[k][c]), [lo1, hi1] = lin(at1[k][c]);
      check(lo1 / hi0 <= 2 + 1e-12 && 2 <= hi1 / lo0 + 1e-12,
        `exposure +1 at (${x},${y}) channel ${c}: linear ratio in [${(lo1 / hi0).toFixed(4)}, ${(hi1 / lo0).toFixed(4)}], not 2`);
    }
  });
  await setInput('exposure', 0);
  check(JSON.stringify(await canvasAt(probes)) === JSON.stringify(at0), 'exposure slider at 0 does not redraw the exposure-0 image');
  await setInput('exposure', 1);
  check(JSON.stringify(await canvasAt(probes)) === JSON.stringify(at1), 'exposure slider at +1 does not draw what key e drew');
  await setInput('exposure', 0);

  // every pixel of every image of the first group, chosen with keys 1..9, at exposure 0 and +10
  // (+10 brings subnormal halves into view), equals the tone-mapped data within one 8-bit step
  const firstGroup = DATA.images.find((im) => !im.reference)?.group ?? '';
  const list = DATA.images.map((im, i) => i).filter((i) => DATA.images[i].reference || DATA.images[i].group === firstGroup);
  for (let n = 0; n < Math.min(9, list.length); n++) {
    const i = list[n];
    await press(String(n + 1));
    if (!check(Number(await js(`return document.getElementById('canvas').dataset.index`)) === i, `key ${n + 1} does not show ${DATA.images[i].name}`)) continue;
    for (const e of [0, 10]) {
      await setInput('exposure', e);
      const px = await canvasAll(), bad = [];
      for (let p = 0; p < W * H; p++) {
        for (let c = 0; c < 3; c++) if (Math.abs(px[4 * p + c] - tone(IMG[i][3 * p + c], e)) > 1) { bad.push(`(${p % W},${Math.floor(p / W)})`); break; }
      }
      check(bad.length === 0, `${DATA.images[i].name} at exposure ${e}: ${bad.length} pixels differ from the data, e.g. ${bad.slice(0, 5).join(' ')}`);
    }
  }
  await setInput('exposure', 0);
  await press(String(list.indexOf(shown) + 1));

  // A/B: image x < divide shows A, the rest B
  const ia = byName(EXPECT.ab.a), ib = byName(EXPECT.ab.b);
  check(ia >= 0 && ib >= 0, `A/B images ${EXPECT.ab.a} / ${EXPECT.ab.b} not in the payload`);
  await click('#ab');
  await setInput('ab-a', ia);
  await setInput('ab-b', ib);
  const want = (i, x, y) => [0, 1, 2].map((c) => tone(IMG[i][3 * (y * W + x) + c], 0));
  const same = (got, exp) => got.every((g, c) => Math.abs(g - exp[c]) <= 1);
  let differing = 0;
  for (const [x, y] of probes) {
    if (!same(want(ia, x, y), want(ib, x, y))) differing++;
    await setInput('divide', x + 1);
    const [l] = await canvasAt([[x, y]]);
    check(same(l, want(ia, x, y)), `A/B divide at ${x + 1}: pixel (${x},${y}) is ${l}, not A's ${want(ia, x, y)}`);
    await setInput('divide', x);
    const [r] = await canvasAt([[x, y]]);
    check(same(r, want(ib, x, y)), `A/B divide at ${x}: pixel (${x},${y}) is ${r}, not B's ${want(ib, x, y)}`);
  }
  check(differing > 0, 'A and B look the same at every probe pixel: the A/B check proves nothing');
  // drag the divide on the canvas from a quarter to three quarters of the image width in view
  await zoomForPointer();
  const row = probes[0] ? probes[0][1] : H >> 1, [v0, v1] = await centreOn(W >> 1, row);
  const x1 = Math.ceil(v0 + (v1 - v0) / 4), x2 = Math.floor(v0 + (3 * (v1 - v0)) / 4);
  const [p1, p2] = [await pixelCentre(x1, row), await pixelCentre(x2, row)];
  await mouse([{ type: 'pointerMove', duration: 0, origin: 'viewport', x: p1[0], y: p1[1] }, { type: 'pointerDown', button: 0 },
    { type: 'pointerMove', duration: 100, origin: 'viewport', x: p2[0], y: p2[1] }, { type: 'pointerUp', button: 0 }]);
  const divide = Number(await js(`return document.getElementById('divide').value`));
  check(Math.abs(divide - (x2 + 0.5)) <= 1, `dragging the divide to x ${x2 + 0.5} left it at ${divide}`);
  const line = await canvasAt([...Array(W).keys()].map((x) => [x, row]));
  const wrong = line.map((px, x) => (same(px, want(x < divide ? ia : ib, x, row)) ? -1 : x)).filter((x) => x >= 0);
  check(wrong.length === 0, `after the drag, row ${row} pixels ${wrong.slice(0, 8).join(', ')} are not ${EXPECT.ab.a} left of ${divide} and ${EXPECT.ab.b} right`);
  await screenshot('ab-divide-dragged');
  await click('#ab');

  // false colour: each view redraws the canvas and relabels the colour bar; the bar's max is the
  // 99th percentile (sorted finite values, index floor(0.99 (n-1))) of the error map
  const errMap = (i, mode) => {
    const a = IMG[i], r = IMG[REF], out = [];
    for (let p = 0; p < W * H; p++) {
      let sum = 0;
      for (let c = 3 * p; c < 3 * p + 3; c++) {
        const d = a[c] - r[c];
        sum += mode === 'abs' ? Math.abs(d) : mode === 'sq' ? d * d : (d * d) / (r[c] * r[c] + 1e-2);
      }
      out.push(sum / 3);
    }
    const f = out.filter(Number.isFinite).sort((u, v) => u - v);
    let hi = f[Math.floor(0.99 * (f.length - 1))];
    if (!(hi > 0)) hi = f[f.length - 1];
    return hi > 0 ? hi : 1;
  };
  const seen = [];
  for (const mode of ['image', 'abs', 'sq', 'relsq']) {
    await click(`button[data-mode="${mode}"]`);
    const bar = await js(`const g = (id) => document.getElementById(id);
      return {visible: !!(g('colorbar') && g('colorbar').offsetParent), min: g('cbar-min').textContent, max: g('cbar-max').textContent,
        maxValue: Number(g('cbar-max').dataset.value), hash: null, mode: g('canvas').dataset.mode};`);
    bar.hash = await canvasHash();
    check(bar.mode === mode, `view ${mode}: the canvas says it shows ${bar.mode}`);
    check(bar.visible && bar.min !== '' && bar.max !== '', `view ${mode}: no colour bar with min/max labels`);
    for (const o of seen) {
      check(o.hash !== bar.hash, `views ${o.mode} and ${mode} draw the same canvas`);
      check(o.max !== bar.max || o.min !== bar.min, `views ${o.mode} and ${mode} have the same colour bar range ${bar.min}..${bar.max}`);
    }
    if (mode !== 'image' && REF >= 0) {
      const hi = errMap(shown, mode);
      check(relClose(bar.maxValue, hi, 1e-5), `view ${mode}: colour bar max ${bar.maxValue}, expected the 99th percentile ${hi}`);
    }
    seen.push({ ...bar, mode });
    await screenshot('view-' + mode);
  }
  // log scale: the colour bar starts three decades below its max, and the map changes
  if (REF >= 0) {
    await click('button[data-mode="abs"]');
    const lin = await canvasHash();
    await click('#log');
    const [lo, hi] = await js(`return ['cbar-min', 'cbar-max'].map((id) => Number(document.getElementById(id).dataset.value))`);
    check(relClose(lo, hi * 1e-3, 1e-9) && (await canvasHash()) !== lin, `log scale: colour bar ${lo}..${hi}, or the map did not change`);
    await screenshot('view-abs-log');
    await click('#log');
  }
  await click('button[data-mode="image"]');

  // wheel over the image zooms in (nearest neighbour, the canvas keeps one pixel per image pixel)
  const width0 = await js(`return document.getElementById('canvas').getBoundingClientRect().width`);
  await centreOn(W >> 1, H >> 1);
  const [cx, cy] = await pixelCentre(W >> 1, H >> 1);
  await actions([{ type: 'wheel', id: 'wheel', actions: [{ type: 'scroll', x: cx, y: cy, deltaX: 0, deltaY: -100, origin: 'viewport' }] }]);
  const width1 = await js(`return document.getElementById('canvas').getBoundingClientRect().width`);
  check(relClose(width1, 2 * width0, 1e-6), `wheel up over the image: width ${width0} → ${width1}, not doubled`);
  await click('#zoom-fit');

  // hover: the inspector shows each image's value and standard error at the pixel
  const hv = EXPECT.hover;
  await centreOn(hv.x, hv.y);
  const [hx, hy] = await pixelCentre(hv.x, hv.y);
  await mouse([{ type: 'pointerMove', duration: 0, origin: 'viewport', x: hx, y: hy }]);
  const insp = await js(`const box = document.getElementById('inspector');
    return {x: box.dataset.x, y: box.dataset.y, cells: [...box.querySelectorAll('[data-image][data-kind]')].map((e) =>
      ({image: e.dataset.image, kind: e.dataset.kind, rgb: e.dataset.rgb, text: e.textContent}))};`);
  check(Number(insp.x) === hv.x && Number(insp.y) === hv.y, `hover over (${hv.x},${hv.y}): the inspector shows (${insp.x},${insp.y})`);
  check(insp.cells.some((c) => c.image === DATA.images[REF]?.name && c.kind === 'value'), 'the inspector does not show the reference');
  for (const [kind, table] of [['value', hv.values || {}], ['stderr', hv.stderr || {}]]) {
    for (const [name, exp] of Object.entries(table)) {
      const cell = insp.cells.find((c) => c.image === name && c.kind === kind);
      if (!check(cell, `the inspector has no ${kind} of ${name}`)) continue;
      const rgb = cell.rgb.split(',').map(Number), text = cell.text.trim().split(/\s+/).map(parseShown);
      // half-float precision (11 significant bits) plus the subnormal step
      check(exp.every((v, c) => relClose(rgb[c], v, 1e-3, 1e-6)), `inspector ${kind} of ${name}: data-rgb ${cell.rgb}, expected ${exp}`);
      check(text.length === 3 && exp.every((v, c) => relClose(text[c], v, 1e-3, 1e-6)), `inspector ${kind} of ${name}: shows "${cell.text}", expected ${exp}`);
    }
  }
  await screenshot('hover');
  await screenshot('tables', '#tables');

  // groups (converge): choosing another group shows that group's image of the same name
  const groups = [...new Set(DATA.images.filter((im) => !im.reference).map((im) => im.group))];
  if (groups.length > 1) {
    const before = await canvasHash(), name = DATA.images[shown].name;
    await setInput('group', groups[1]);
    const now = Number(await js(`return document.getElementById('canvas').dataset.index`));
    check(DATA.images[now]?.group === groups[1] && DATA.images[now]?.name === name,
      `group ${groups[1]}: the view shows image ${now}, not ${name} of that group`);
    check((await canvasHash()) !== before, `group ${groups[1]}: the canvas did not change`);
    await screenshot('group-' + groups[1].replace(/\W+/g, '-'));
  }

  await pageErrors();
}

/** No JavaScript errors, no failed or outside loads. */
async function pageErrors() {
  const errors = await js('return window.__vrptErrors || ["window.__vrptErrors missing"]');
  check(errors.length === 0, 'JavaScript errors on the page: ' + errors.join(' | '));
  const log = await wd('POST', s('/se/log'), { type: 'browser' });
  const severe = log.filter((e) => e.level === 'SEVERE' || e.level === 'WARNING');
  check(severe.length === 0, 'browser console: ' + severe.map((e) => `${e.level} ${e.message}`).join(' | '));
  const outside = await js(`return performance.getEntriesByType('resource').map((e) => e.name)
    .filter((n) => !n.startsWith('file:') && !n.startsWith('data:') && !n.startsWith('blob:'))`);
  check(outside.length === 0, 'the page loaded from outside: ' + outside.join(', '));
}

// a hung browser must not hang CI: give up after 5 minutes, closing what we started
const watchdog = setTimeout(async () => {
  console.log('FAIL: the check did not finish in 300 s');
  if (session) await Promise.race([wd('DELETE', `/session/${session}`).catch(() => {}), new Promise((r) => setTimeout(r, 5000))]);
  if (driver) driver.kill();
  process.exit(1);
}, 300_000);

try {
  await start();
  await run();
} catch (e) {
  failures.push('run aborted: ' + e.message);
  console.log('FAIL: run aborted: ' + e.message);
} finally {
  if (session) await wd('DELETE', `/session/${session}`).catch(() => {});
  if (driver && driver.exitCode === null) {
    const gone = new Promise((r) => driver.once('exit', r));
    driver.kill();
    await Promise.race([gone, new Promise((r) => setTimeout(r, 5000))]);
  }
}
clearTimeout(watchdog);
console.log(`report check took ${((Date.now() - started) / 1000).toFixed(1)} s`);
console.log(`${passed} passed, ${failures.length} failed`);
process.exit(failures.length ? 1 : 0);
