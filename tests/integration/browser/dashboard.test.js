#!/usr/bin/env node
// dashboard.test.js -- grainpack's dashboard (GET /) driven in a real browser: Debian's chromium
// through puppeteer-core (pinned in package.json / package-lock.json; `npm ci` in this folder,
// done by `deploy/install-deps.sh --test`). Run by tests/integration/test_dashboard_browser.py
// (ctest it_test_dashboard_browser), which starts the daemon and passes:
//
//   node dashboard.test.js --url=http://127.0.0.1:PORT --out=SCREENSHOT_DIR --chromium=/usr/bin/chromium [--smoke]
//
// The full run, for each kind: chooses it in #kind, fills the quick fields and (3D) shrinks the
// spec in #spec, submits through #submit, waits for its row in #jobs to reach `succeeded`, opens
// it, compares the #summary with GET /v1/jobs/{id}/result fetched here (not through the page),
// loads every view in #views (each picture must load, and the SVG fetched here must be XML with
// an <svg> root) and saves a screenshot of each; then cancels a long 2D job through #cancel, and
// uploads a grain outline file into #q-outlines, analyses it (#analyse) and submits a job from it;
// reloads the page at #/jobs/{id}. Any console error, uncaught page error or CSP violation fails.
// --smoke only loads the page, checks the console and saves one screenshot (to check the set-up).
// Exit status 0 = pass; failures print what went wrong and save FAILED-*.png in SCREENSHOT_DIR.
'use strict';

const fs = require('fs');
const path = require('path');

let puppeteer;
try {
  puppeteer = require('puppeteer-core');
} catch (e) {
  console.error('FAIL: puppeteer-core is not installed in ' + __dirname +
    ' (run `bash deploy/install-deps.sh --test`, or `npm ci` in that folder): ' + e.message);
  process.exit(1);
}

// ---- arguments ----
const args = {};
for (const a of process.argv.slice(2)) {
  const m = /^--([a-z-]+)(?:=(.*))?$/.exec(a);
  if (!m) { console.error('bad argument ' + a); process.exit(2); }
  args[m[1]] = m[2] === undefined ? true : m[2];
}
if (!args.url || !args.out) {
  console.error('usage: node dashboard.test.js --url=BASE --out=DIR [--chromium=PATH] [--smoke]');
  process.exit(2);
}
const BASE = args.url.replace(/\/+$/, '');
const OUT = path.resolve(args.out);
const CHROMIUM = args.chromium || '/usr/bin/chromium';
const TIME_SCALE = parseFloat(process.env.GPD_TEST_TIME_SCALE || '1') || 1;
const T = (ms) => Math.round(ms * TIME_SCALE);
fs.mkdirSync(OUT, { recursive: true });

const FINAL = ['succeeded', 'failed', 'cancelled'];
const KINDS = {
  'fourier-voronoi-2d': {
    short: '2d', main: 'solid_fraction', views: ['packing', 'cells', 'size', 'orientation', 'descriptors'],
    quick: { '#q-particles': 300, '#q-seed': 42 },
    // checked against GET /v1/jobs/{id}/spec: the form's values reached the daemon
    expectSpec: { particles: 300, seed: 42 },
    // the example a new user runs first meets its laws: no warning
    noWarnings: true,
  },
  'spheres-3d': {
    short: '3d', main: 'porosity', views: ['section', 'psd'],
    // a 6 mm box of 1-2 mm spheres (a few dozen, about a second), no tiling
    editSpec: (s) => {
      s.box = [0.006, 0.006, 0.006];
      s.sieve = [[1, 0], [2, 100]];
      s.sieve_units = 'mm';
      s.porosity = 0.5;
      delete s.tiling;
      return s;
    },
    quick: { '#q-seed': 7, '#q-porosity': 0.5 },
    expectSpec: { seed: 7, box: [0.006, 0.006, 0.006], porosity: 0.5 },
  },
};
// a 2D job that runs until cancelled: many particles, an IMC threshold it cannot reach
const LONG_2D = { particles: 40000, imc: { threshold: 1e-9, max_steps: 1000000000 } };

// ---- reporting ----
const problems = [];     // console errors, page errors, CSP violations, failed requests
const shots = [];
let page = null;
let step = 'start';

function log(msg) { console.log('[' + new Date().toISOString().slice(11, 23) + '] ' + msg); }
function fail(msg) { throw new Error('[' + step + '] ' + msg); }
function check(cond, msg) { if (!cond) fail(msg); }
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// the visible part of the page (its panels scroll by themselves; scroll to what matters first)
async function shot(name, p) {
  const file = path.join(OUT, name + '.png');
  await (p || page).screenshot({ path: file });
  shots.push(file);
  console.log('screenshot: ' + file);
  return file;
}

// ---- the test's own HTTP client (node's fetch; no Origin header, like curl) ----
async function api(pathAndQuery, opts) {
  const r = await fetch(BASE + pathAndQuery, opts);
  const body = await r.text();
  return { status: r.status, headers: r.headers, body };
}
async function apiJson(pathAndQuery) {
  const r = await api(pathAndQuery);
  check(r.status === 200, 'GET ' + pathAndQuery + ' -> ' + r.status + ' ' + r.body.slice(0, 300));
  return JSON.parse(r.body);
}

// ---- numbers as the page shows them ----
// "0.650", "65.0 %", "1.2e-3", "12,000", "−0.5" -> {value, tol}: tol is half a unit of the last
// shown digit, so the shown number must round to the real one.
function shownNumber(text) {
  const t = String(text).replace(/\u2212/g, '-').replace(/(\d)[,\u2009\u202f ](?=\d{3}\b)/g, '$1');
  const m = /([-+]?(?:\d+\.?\d*|\.\d+))(?:[eE]([-+]?\d+))?\s*(%)?/.exec(t);
  if (!m) return null;
  const mant = m[1];
  const exp = m[2] ? parseInt(m[2], 10) : 0;
  const dot = mant.indexOf('.');
  const decimals = dot < 0 ? 0 : mant.length - dot - 1;
  let value = parseFloat(mant) * Math.pow(10, exp);
  let tol = 0.5 * Math.pow(10, exp - decimals);
  if (m[3]) { value /= 100; tol /= 100; }
  return { value, tol: tol * (1 + 1e-9) + 1e-15, text: m[0] };
}
function sameShown(text, actual, what) {
  const n = shownNumber(text);
  check(n !== null, what + ': no number in "' + text + '"');
  check(Math.abs(n.value - actual) <= n.tol,
    what + ': the page shows "' + text.trim() + '" (' + n.value + ' +- ' + n.tol + '), the result has ' + actual);
}

// ---- DOM helpers ----
async function attr(sel, name) {
  return page.$eval(sel, (el, n) => el.getAttribute(n), name).catch(() => null);
}
async function waitAttr(sel, name, okValues, timeout, what) {
  try {
    await page.waitForFunction((s, n, ok) => {
      const el = document.querySelector(s);
      return !!el && ok.includes(el.getAttribute(n));
    }, { timeout, polling: 100 }, sel, name, okValues);
  } catch (e) {
    fail((what || sel) + ': ' + name + ' is ' + JSON.stringify(await attr(sel, name)) +
      ', not one of ' + JSON.stringify(okValues) + ' after ' + timeout + ' ms');
  }
  return attr(sel, name);
}
// sets an <input>/<textarea> the way a user does: focus, select all, type, then leave the field
async function typeInto(sel, value) {
  const el = await page.$(sel);
  check(el, 'no ' + sel);
  await el.focus();
  await page.$eval(sel, (e) => { if (typeof e.select === 'function') e.select(); });
  await page.keyboard.press('Backspace');
  await el.type(String(value));
  await page.$eval(sel, (e) => e.blur());
}
// sets a (long) textarea at once, firing input and change as typing would
async function setText(sel, value) {
  check(await page.$(sel), 'no ' + sel);
  await page.$eval(sel, (e, v) => {
    e.focus();
    e.value = v;
    e.dispatchEvent(new Event('input', { bubbles: true }));
    e.dispatchEvent(new Event('change', { bubbles: true }));
    e.blur();
  }, value);
}
async function jobIds() {
  return page.$$eval('#jobs tr.job', (rows) => rows.map((r) => r.getAttribute('data-job-id')));
}
const rowSel = (id) => '#jobs tr.job[data-job-id="' + id + '"]';

// ---- steps ----
async function openPage() {
  const r = await page.goto(BASE + '/', { waitUntil: 'load', timeout: T(30000) });
  check(r && r.status() === 200, 'GET / -> ' + (r ? r.status() : 'no response'));
  if (args.smoke) return; // any page will do
  await page.waitForSelector('#kind', { timeout: T(10000) });
  await page.waitForSelector('#jobs', { timeout: T(10000) });
}

async function submitThroughForm(kind, conf, extra) {
  const kinds = await page.$$eval('#kind option', (os) => os.map((o) => o.value));
  check(kinds.includes(kind), '#kind has no option ' + kind + ' (has ' + kinds.join(', ') + ')');
  await page.select('#kind', kind);
  // #spec shows the example spec of the selected kind
  try {
    await page.waitForFunction((k) => {
      try { return JSON.parse(document.querySelector('#spec').value).kind === k; } catch (e) { return false; }
    }, { timeout: T(5000), polling: 100 }, kind);
  } catch (e) {
    fail('#spec does not hold a spec of kind ' + kind + ': ' + (await page.$eval('#spec', (t) => t.value)).slice(0, 300));
  }
  let spec = JSON.parse(await page.$eval('#spec', (t) => t.value));
  if (conf.editSpec) spec = conf.editSpec(spec);
  if (extra && extra.spec) spec = Object.assign(spec, extra.spec(spec));
  await setText('#spec', JSON.stringify(spec, null, 2));
  const quick = Object.assign({}, conf.quick, (extra && extra.quick) || {});
  for (const [sel, v] of Object.entries(quick)) {
    check(await page.$(sel), 'the quick field ' + sel + ' is missing for ' + kind);
    await typeInto(sel, v);
  }
  const before = new Set(await jobIds());
  await page.click('#submit');
  let id = null;
  const deadline = Date.now() + T(15000);
  while (!id && Date.now() < deadline) {
    id = (await jobIds()).find((x) => x && !before.has(x)) || null;
    if (!id) await sleep(100);
  }
  if (!id) {
    const msg = await page.$eval('#submit-msg', (e) => e.textContent).catch(() => '(no #submit-msg)');
    fail('no new row in #jobs after submitting ' + kind + '; #submit-msg: ' + JSON.stringify(msg));
  }
  log(kind + ': submitted through the form: job ' + id);
  return id;
}

async function checkSpecSent(id, expect) {
  const spec = await apiJson('/v1/jobs/' + id + '/spec');
  for (const [k, v] of Object.entries(expect)) {
    check(JSON.stringify(spec[k]) === JSON.stringify(v),
      'the daemon got ' + k + ' = ' + JSON.stringify(spec[k]) + ', the form was given ' + JSON.stringify(v));
  }
}

async function openJob(id) {
  await page.click(rowSel(id));
  await waitAttr('#detail', 'data-job-id', [id], T(10000), '#detail after clicking the row');
  const hash = await page.evaluate(() => location.hash);
  check(hash === '#/jobs/' + id, 'location.hash is ' + JSON.stringify(hash) + ', not #/jobs/' + id);
}

// every #summary row whose quantity is in the result's stats must show the same numbers
async function checkSummary(id, conf, stats) {
  const mainSel = '#summary tr[data-quantity="' + conf.main + '"]';
  try {
    await page.waitForFunction((s) => {
      const td = document.querySelector(s + ' td.achieved');
      return !!td && /\d/.test(td.textContent);
    }, { timeout: T(10000), polling: 100 }, mainSel);
  } catch (e) {
    fail('#summary has no ' + conf.main + ' row with an achieved value');
  }
  const rows = await page.$$eval('#summary tr[data-quantity]', (trs) => trs.map((tr) => ({
    q: tr.getAttribute('data-quantity'),
    target: tr.querySelector('td.target') ? tr.querySelector('td.target').textContent : null,
    achieved: tr.querySelector('td.achieved') ? tr.querySelector('td.achieved').textContent : null,
  })));
  const main = rows.find((r) => r.q === conf.main);
  check(main.target !== null && /\d/.test(main.target), conf.main + ': no target shown (td.target: ' + JSON.stringify(main.target) + ')');
  const st = stats[conf.main];
  check(st && typeof st.target === 'number' && typeof st.achieved === 'number', 'result stats.' + conf.main + ' is ' + JSON.stringify(st));
  sameShown(main.target, st.target, conf.main + ' target');
  sameShown(main.achieved, st.achieved, conf.main + ' achieved');
  let compared = 0;
  for (const r of rows) {
    const s = stats[r.q];
    if (s === undefined || r.achieved === null || !/\d/.test(r.achieved)) continue;
    if (typeof s === 'number') {
      sameShown(r.achieved, s, r.q + ' achieved');
      compared++;
    } else if (s && typeof s === 'object' && typeof s.achieved === 'number') {
      sameShown(r.achieved, s.achieved, r.q + ' achieved');
      if (typeof s.target === 'number' && r.target !== null && /\d/.test(r.target)) sameShown(r.target, s.target, r.q + ' target');
      compared++;
    }
  }
  const timings = await page.$eval('#timings', (e) => e.textContent.trim()).catch(() => null);
  check(timings, '#timings is missing or empty');
  log('summary: ' + rows.map((r) => r.q + ' ' + (r.target || '-').trim() + ' / ' + (r.achieved || '-').trim()).join('; ') +
    ' (' + compared + ' rows compared with the result)');
}

let xmlPage = null;   // a blank page whose DOMParser checks the SVG text fetched by the test
async function checkSvgText(id, view, extraQuery) {
  const r = await api('/v1/jobs/' + id + '/svg?view=' + encodeURIComponent(view) + (extraQuery || ''));
  check(r.status === 200, 'GET svg view=' + view + ' -> ' + r.status + ' ' + r.body.slice(0, 200));
  check(/^image\/svg\+xml/.test(r.headers.get('content-type') || ''), 'svg view=' + view + ' has Content-Type ' + r.headers.get('content-type'));
  const root = await xmlPage.evaluate((text) => {
    const doc = new DOMParser().parseFromString(text, 'image/svg+xml');
    const err = doc.getElementsByTagName('parsererror')[0];
    if (err) return { error: err.textContent.slice(0, 300) };
    return { name: doc.documentElement.localName, ns: doc.documentElement.namespaceURI };
  }, r.body);
  check(!root.error, 'svg view=' + view + ' is not well-formed XML: ' + root.error);
  check(root.name === 'svg' && root.ns === 'http://www.w3.org/2000/svg',
    'svg view=' + view + ' has root <' + root.name + '> in ' + root.ns);
  fs.writeFileSync(path.join(OUT, id.slice(0, 8) + '-' + view + '.svg'), r.body);
}

async function waitPicture(id, view, what) {
  try {
    await page.waitForFunction((v, j) => {
      const img = document.querySelector('#picture');
      return !!img && img.getAttribute('data-view') === v && img.getAttribute('data-job-id') === j &&
        ['loaded', 'error'].includes(img.getAttribute('data-state'));
    }, { timeout: T(30000), polling: 100 }, view, id);
  } catch (e) {
    const st = await page.$eval('#picture', (i) => [i.getAttribute('data-view'), i.getAttribute('data-job-id'), i.getAttribute('data-state')]).catch(() => null);
    fail(what + ': #picture (data-view, data-job-id, data-state) is ' + JSON.stringify(st) + ' after ' + T(30000) + ' ms');
  }
  const img = await page.$eval('#picture', (i) => ({ state: i.getAttribute('data-state'), w: i.naturalWidth, h: i.naturalHeight, src: i.currentSrc || i.src }));
  check(img.state === 'loaded', what + ': #picture data-state is ' + img.state + ' (src ' + img.src + ')');
  check(img.w > 0 && img.h > 0, what + ': #picture did not decode (naturalWidth ' + img.w + ', src ' + img.src + ')');
  return img;
}

async function checkViews(id, kind, conf) {
  const views = await page.$$eval('#views button[data-view]', (bs) => bs.map((b) => b.getAttribute('data-view')));
  for (const v of conf.views) check(views.includes(v), '#views has no button for ' + v + ' (has ' + views.join(', ') + ')');
  for (const view of views) {
    step = kind + ' view ' + view;
    await page.click('#views button[data-view="' + view + '"]');
    await waitPicture(id, view, 'view ' + view);
    const dl = await page.$eval('a#svg-download', (a) => a.href).catch(() => null);
    check(dl, 'no a#svg-download');
    const u = new URL(dl);
    check(u.pathname === '/v1/jobs/' + id + '/svg' && u.searchParams.get('view') === view,
      'a#svg-download points to ' + dl + ', not this job\'s ' + view);
    await checkSvgText(id, view);
    await page.$eval('#picture', (e) => e.scrollIntoView({ block: 'center' }));
    await shot(conf.short + '-' + view);
    if (view === 'section') {
      const z = await page.$('#z');
      check(z, 'the 3D section view has no #z range');
      const { min, max, value, src } = await page.$eval('#z', (e) => ({
        min: parseFloat(e.min), max: parseFloat(e.max), value: parseFloat(e.value), src: document.querySelector('#picture').src,
      }));
      // a quarter of the way up (three quarters if that is where it is): a section through spheres
      let target = min + 0.25 * (max - min);
      if (Math.abs(target - value) < 0.05 * (max - min)) target = min + 0.75 * (max - min);
      await page.$eval('#z', (e, v) => {
        e.value = String(v);
        e.dispatchEvent(new Event('input', { bubbles: true }));
        e.dispatchEvent(new Event('change', { bubbles: true }));
      }, target);
      try {
        await page.waitForFunction((old) => {
          const i = document.querySelector('#picture');
          return i.src !== old && i.getAttribute('data-state') === 'loaded';
        }, { timeout: T(15000), polling: 100 }, src);
      } catch (e) {
        fail('moving #z to ' + target + ' did not load another section (src ' + (await page.$eval('#picture', (i) => i.src)) + ')');
      }
      const img = await waitPicture(id, view, 'section after moving #z');
      const zq = new URL(img.src).searchParams.get('z');
      if (zq !== null) await checkSvgText(id, view, '&z=' + encodeURIComponent(zq));
      await page.$eval('#picture', (e) => e.scrollIntoView({ block: 'center' }));
      await shot(conf.short + '-section-z');
    }
  }
  return views;
}

async function checkExports(id) {
  const links = await page.$$eval('#exports a[data-format]', (as) => as.map((a) => ({ f: a.getAttribute('data-format'), href: a.href })));
  check(links.length > 0, '#exports has no a[data-format]');
  for (const l of links) {
    const u = new URL(l.href);
    check(u.pathname === '/v1/jobs/' + id + '/export' && u.searchParams.get('format') === l.f,
      'export link ' + l.f + ' points to ' + l.href);
    const r = await api(u.pathname + u.search);
    check(r.status === 200, 'export ' + l.f + ' -> ' + r.status + ' ' + r.body.slice(0, 200));
    check(/attachment/.test(r.headers.get('content-disposition') || ''), 'export ' + l.f + ' is not an attachment');
  }
  return links.map((l) => l.f);
}

async function runKind(kind) {
  const conf = KINDS[kind];
  step = kind + ' submit';
  const id = await submitThroughForm(kind, conf);
  await checkSpecSent(id, conf.expectSpec);
  step = kind + ' wait';
  const status = await waitAttr(rowSel(id), 'data-status', FINAL, T(120000), 'the row of job ' + id);
  if (status !== 'succeeded') {
    const j = await apiJson('/v1/jobs/' + id);
    fail('job ' + id + ' ended ' + status + ': ' + JSON.stringify(j.error));
  }
  const j = await apiJson('/v1/jobs/' + id);
  check(j.status === 'succeeded', 'the row says succeeded, the API says ' + j.status);
  step = kind + ' open';
  await openJob(id);
  step = kind + ' summary';
  const result = await apiJson('/v1/jobs/' + id + '/result');
  if (conf.noWarnings) {
    check(Array.isArray(result.warnings) && result.warnings.length === 0,
      'the example spec of ' + kind + ' gave warnings: ' + JSON.stringify(result.warnings));
  }
  await checkSummary(id, conf, result.stats);
  step = kind + ' views';
  const views = await checkViews(id, kind, conf);
  step = kind + ' exports';
  const formats = await checkExports(id);
  log(kind + ': job ' + id + ' ok; views ' + views.join(', ') + '; exports ' + formats.join(', '));
  return id;
}

async function cancelThroughPage() {
  const kind = 'fourier-voronoi-2d';
  step = 'cancel submit';
  const id = await submitThroughForm(kind, KINDS[kind], {
    spec: (s) => ({ imc: Object.assign({}, s.imc || {}, LONG_2D.imc) }),
    quick: { '#q-particles': LONG_2D.particles, '#q-seed': 7 },
  });
  await checkSpecSent(id, { particles: LONG_2D.particles });
  step = 'cancel open';
  await openJob(id);
  await waitAttr(rowSel(id), 'data-status', ['queued', 'running'], T(5000));
  await page.waitForSelector('#cancel:not([disabled])', { visible: true, timeout: T(10000) })
    .catch(() => fail('no enabled, visible #cancel for job ' + id));
  await page.click('#cancel');
  step = 'cancel wait';
  await waitAttr(rowSel(id), 'data-status', ['cancelled'], T(30000), 'the cancelled row');
  const j = await apiJson('/v1/jobs/' + id);
  check(j.status === 'cancelled', 'the API says ' + j.status + ' after #cancel');
  await shot('2d-cancelled');
  log('cancel: job ' + id + ' cancelled through #cancel');
}

// a grain outline file (text, one outline a line) of 30 grains from D2 0.1, D3 0.05, D8 0.02
function outlineFile() {
  const lines = ['# 30 grains, x1 y1 x2 y2 ...'];
  let seed = 12345;
  const rnd = () => { seed = (seed * 1103515245 + 12345) % 2147483648; return seed / 2147483648; };
  for (let g = 0; g < 30; g++) {
    const ph = [2, 3, 8].map(() => (rnd() * 2 - 1) * Math.PI), nums = [];
    for (let i = 0; i < 64; i++) {
      const t = 2 * Math.PI * i / 64;
      const r = 1 + 0.1 * Math.cos(2 * t - ph[0]) + 0.05 * Math.cos(3 * t - ph[1]) + 0.02 * Math.cos(8 * t - ph[2]);
      nums.push((10 * g + r * Math.cos(t)).toFixed(5), (r * Math.sin(t)).toFixed(5));
    }
    lines.push(nums.join(' '));
  }
  const file = path.join(OUT, 'outlines.txt');
  fs.writeFileSync(file, lines.join('\n') + '\n');
  return file;
}

// the 2D form with an uploaded outline file: the count shown, the analysis (POST
// /v1/shapes/analyze) shown, and a job submitted with the file's outlines as shape.outlines
async function outlinesThroughPage() {
  const kind = 'fourier-voronoi-2d';
  step = 'outlines upload';
  await page.select('#kind', kind);
  const input = await page.$('#q-outlines');
  check(input, 'no #q-outlines for ' + kind);
  await input.uploadFile(outlineFile());
  await page.waitForFunction(() => /^30 outlines/.test(document.querySelector('#outlines-info').textContent),
    { timeout: T(10000), polling: 100 }).catch(async () => fail('#outlines-info says ' +
      JSON.stringify(await page.$eval('#analyse-msg', (e) => e.textContent))));
  const spec = JSON.parse(await page.$eval('#spec', (t) => t.value));
  check(spec.shape && Array.isArray(spec.shape.outlines) && spec.shape.outlines.length === 30 &&
    spec.shape.outlines[0].length === 64, 'the spec\'s shape after the upload: ' + JSON.stringify(spec.shape).slice(0, 200));
  step = 'outlines analyse';
  await page.click('#analyse');
  await page.waitForFunction(() => /D2 /.test(document.querySelector('#analyse-msg').textContent),
    { timeout: T(20000), polling: 100 }).catch(async () => fail('#analyse-msg says ' +
      JSON.stringify(await page.$eval('#analyse-msg', (e) => e.textContent))));
  const msg = await page.$eval('#analyse-msg', (e) => e.textContent);
  const d2 = /D2 ([0-9.]+)/.exec(msg), d3 = /D3 ([0-9.]+)/.exec(msg);
  check(d2 && Math.abs(parseFloat(d2[1]) - 0.1) < 0.005 && d3 && Math.abs(parseFloat(d3[1]) - 0.05) < 0.003,
    '#analyse-msg: ' + msg);
  await page.$eval('#analyse-msg', (e) => e.scrollIntoView({ block: 'center' }));
  await shot('2d-outlines');
  log('outlines: ' + msg);
  step = 'outlines submit';
  const before = new Set(await jobIds());
  await typeInto('#q-particles', 100);
  await page.click('#submit');
  let id = null;
  const deadline = Date.now() + T(15000);
  while (!id && Date.now() < deadline) {
    id = (await jobIds()).find((x) => x && !before.has(x)) || null;
    if (!id) await sleep(100);
  }
  check(id, 'no new row after submitting the outlines: ' + (await page.$eval('#submit-msg', (e) => e.textContent)));
  const sent = await apiJson('/v1/jobs/' + id + '/spec');
  check(sent.shape && sent.shape.outlines && sent.shape.outlines.length === 30 && sent.particles === 100,
    'the daemon got shape ' + JSON.stringify(sent.shape).slice(0, 200));
  const status = await waitAttr(rowSel(id), 'data-status', FINAL, T(120000), 'the row of job ' + id);
  check(status === 'succeeded', 'the job from the outline file ended ' + status);
  log('outlines: job ' + id + ' from the uploaded file succeeded');
}

async function reloadAt(id, conf) {
  step = 'reload at #/jobs/' + id;
  await page.evaluate((h) => { location.hash = h; }, '#/jobs/' + id);
  await page.reload({ waitUntil: 'load', timeout: T(30000) });
  await waitAttr('#detail', 'data-job-id', [id], T(10000), '#detail after the reload');
  await page.waitForSelector('#summary tr[data-quantity="' + conf.main + '"] td.achieved', { timeout: T(10000) })
    .catch(() => fail('the reloaded page shows no ' + conf.main + ' for job ' + id));
  await shot(conf.short + '-reloaded');
}

async function deepLink(browser, id, conf) {
  step = 'new tab at #/jobs/' + id;
  const p2 = await browser.newPage();
  watch(p2, 'tab2');
  await p2.setViewport({ width: 1280, height: 1000 });
  await p2.goto(BASE + '/#/jobs/' + id, { waitUntil: 'load', timeout: T(30000) });
  try {
    await p2.waitForFunction((j) => {
      const d = document.querySelector('#detail');
      return d && d.getAttribute('data-job-id') === j;
    }, { timeout: T(10000), polling: 100 }, id);
  } catch (e) {
    fail('a page opened at #/jobs/' + id + ' does not show that job');
  }
  await shot(conf.short + '-deeplink', p2);
  await p2.close();
}

function watch(p, tag) {
  p.on('console', (m) => {
    if (m.type() === 'error') {
      const loc = m.location() || {};
      // the browser asks for /favicon.ico by itself (the page names no icon): its 404 is not the page's
      if (/^Failed to load resource/.test(m.text()) && /\/favicon\.ico$/.test(loc.url || '')) {
        log(tag + ' (ignored) ' + m.text() + ' ' + loc.url);
        return;
      }
      problems.push(tag + ' console error: ' + m.text() + (loc.url ? ' (' + loc.url + (loc.lineNumber !== undefined ? ':' + loc.lineNumber : '') + ')' : ''));
    }
  });
  p.on('pageerror', (e) => problems.push(tag + ' uncaught error: ' + (e && e.message ? e.message : String(e))));
  p.on('requestfailed', (r) => {
    const why = r.failure() ? r.failure().errorText : '?';
    // an <img> whose src is replaced while it loads, or a poll cut by a reload, is aborted: not an error
    if (why !== 'net::ERR_ABORTED') problems.push(tag + ' request failed: ' + r.method() + ' ' + r.url() + ' ' + why);
  });
  p.on('dialog', (d) => { log(tag + ' dialog (' + d.type() + '): ' + d.message() + ' -> accept'); d.accept(); });
  // the browser also logs CSP violations to the console; this names the directive
  p.evaluateOnNewDocument(() => {
    document.addEventListener('securitypolicyviolation', (e) => {
      console.error('CSP violation: ' + e.violatedDirective + ' blocked ' + (e.blockedURI || 'inline') +
        ' at ' + e.sourceFile + ':' + e.lineNumber);
    });
  });
}

async function main() {
  log('chromium ' + CHROMIUM + ', puppeteer-core ' + require('puppeteer-core/package.json').version +
    ', node ' + process.version + ', dashboard ' + BASE + '/');
  const browser = await puppeteer.launch({
    executablePath: CHROMIUM,
    headless: true, // --headless=new
    args: ['--no-sandbox', '--disable-dev-shm-usage', '--disable-gpu', '--no-first-run',
      '--no-default-browser-check', '--disable-extensions', '--lang=en-US'],
    protocolTimeout: T(120000),
    timeout: T(60000),
  });
  let ok = false;
  try {
    log('browser ' + (await browser.version()));
    // the launch's blank tab parses the SVGs; the dashboard's tab is opened after it, so that it is
    // the visible one (a hidden tab gets no IntersectionObserver callbacks: clicks would hang)
    xmlPage = (await browser.pages())[0] || await browser.newPage();
    page = await browser.newPage();
    watch(page, 'page');
    await page.setViewport({ width: 1280, height: 1000 });
    page.setDefaultTimeout(T(30000));
    await page.bringToFront();

    step = 'open';
    await openPage();
    if (args.smoke) {
      await sleep(1000);
      await shot('smoke');
    } else {
      for (const sel of ['#kind', '#spec', '#submit', '#submit-msg', '#jobs', '#page-prev', '#page-next', '#detail']) {
        check(await page.$(sel), 'the page has no ' + sel);
      }
      const id2d = await runKind('fourier-voronoi-2d');
      const id3d = await runKind('spheres-3d');
      await cancelThroughPage();
      await outlinesThroughPage();
      await reloadAt(id2d, KINDS['fourier-voronoi-2d']);
      await deepLink(browser, id3d, KINDS['spheres-3d']);
    }
    step = 'console';
    await sleep(500); // late console messages
    check(problems.length === 0, 'the browser reported ' + problems.length + ' problem(s):\n  ' + problems.join('\n  '));
    ok = true;
  } catch (e) {
    const msg = e && e.message ? e.message : String(e);
    console.error('FAIL ' + (msg.startsWith('[') ? msg : '[' + step + '] ' + msg));
    if (process.env.GP_BROWSER_TRACE && e && e.stack) console.error(e.stack);
    if (problems.length && step !== 'console') console.error('browser problems so far:\n  ' + problems.join('\n  '));
    if (page) {
      try { await shot('FAILED-' + step.replace(/[^A-Za-z0-9]+/g, '_')); } catch (e2) { console.error('no failure screenshot: ' + e2.message); }
    }
  } finally {
    await browser.close().catch(() => {});
  }
  console.log((ok ? 'PASS' : 'FAIL') + (args.smoke ? ' (smoke)' : '') + '; ' + shots.length + ' screenshot(s) in ' + OUT);
  process.exit(ok ? 0 : 1);
}

main().catch((e) => { console.error('FAIL ' + (e && e.stack ? e.stack : e)); process.exit(1); });
