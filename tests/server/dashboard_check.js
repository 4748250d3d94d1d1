// dashboard_check.js -- runs the dashboard page's script (server/http/dashboard.html as served, the
// kinds filled in) in node against a small stand-in DOM and a stand-in service (fetch answered
// from fixtures), and checks how the page behaves:
//  - the example spec of every kind is compact (short arrays on one line, < 20 lines) and parses
//    back to the same JSON; the quick fields edit the spec;
//  - the job list: one tr.job per job with data-job-id / data-status, kind, particles, seed,
//    headline achieved value; rows updated in place (the same element after a refresh that
//    changes the status), not touched while a mouse button is down; paging;
//  - a cancelled job is grey (no running bar), a failed job red with its error message, a job
//    with warnings amber with a marker;
//  - the location hash #/jobs/{id} selects the job (also on a fresh load); selecting sets it;
//  - the result panel (#summary, tr[data-quantity] with td.target / td.achieved) for a 2D and a
//    3D summary fixture shows the fixture's numbers; #timings; without a summary it falls back
//    to the job's progress detail;
//  - pictures: a button per view, img#picture with data-view / data-job-id / data-state, the
//    download link, the z slider of the section view re-requesting the picture;
//  - the header says the service's state in words;
//  - grain outlines from a file (2D): the parser of both formats (JSON, one outline a line),
//    the file input that makes them the spec's shape.outlines, the analyse button.
// Usage: node tests/server/dashboard_check.js PAGE.html   (tests/server/test_dashboard.c runs it; exit 0 = ok)
"use strict";
const fs = require("fs");
const vm = require("vm");

/* ------------------------------------------------------------------ a stand-in DOM */

class Elem {
  constructor(tag, id) {
    this.tagName = tag; this.id = id || ""; this.children = []; this.attrs = {}; this.style = {};
    this.text = ""; this.parentNode = null; this._value = undefined;
    this.checked = false; this.disabled = false;
  }
  setAttribute(k, v) { this.attrs[k] = String(v); }
  getAttribute(k) { return k in this.attrs ? this.attrs[k] : null; }
  removeAttribute(k) { delete this.attrs[k]; }
  hasAttribute(k) { return k in this.attrs; }
  detach() {
    if (this.parentNode) {
      const p = this.parentNode.children, i = p.indexOf(this);
      if (i >= 0) p.splice(i, 1);
      this.parentNode = null;
    }
  }
  appendChild(c) { c.detach(); c.parentNode = this; this.children.push(c); return c; }
  insertBefore(c, ref) {
    if (ref === null || ref === undefined) return this.appendChild(c);
    c.detach();
    const i = this.children.indexOf(ref);
    if (i < 0) throw new Error("insertBefore: ref is not a child");
    c.parentNode = this;
    this.children.splice(i, 0, c);
    return c;
  }
  removeChild(c) {
    if (c.parentNode !== this) throw new Error("removeChild: not a child");
    c.detach();
    return c;
  }
  get nextSibling() {
    if (!this.parentNode) return null;
    const p = this.parentNode.children;
    return p[p.indexOf(this) + 1] || null;
  }
  get value() {
    if (this._value !== undefined) return this._value;
    const opt = this.children.find((c) => c.tagName === "option");
    return opt ? (opt.getAttribute("value") !== null ? opt.getAttribute("value") : opt.textContent) : "";
  }
  set value(v) { this._value = String(v); }
  get className() { return this.attrs["class"] || ""; }
  set className(v) { this.attrs["class"] = String(v); }
  classes() { return this.className.split(/\s+/).filter(Boolean); }
  get textContent() { return this.text + this.children.map((c) => c.textContent).join(""); }
  set textContent(v) { this.text = String(v); this.children.slice().forEach((c) => c.detach()); }
  // elements below (and including) this one that pass f, depth first
  all(f, out = []) {
    if (f(this)) out.push(this);
    this.children.forEach((c) => c.all(f, out));
    return out;
  }
  find(cls) { return this.all((e) => e.classes().includes(cls)); }
  byAttr(k, v) { return this.all((e) => e.getAttribute(k) !== null && (v === undefined || e.getAttribute(k) === String(v))); }
  one(k, v) { return this.byAttr(k, v)[0] || null; }
}

/* a page's script in a fresh context: the DOM, the location and a service answering from
 * routes ({path: body | function (path, opts) -> {status, body}}); every request logged */
function boot(page, hash, routes) {
  const byId = {}, docH = {}, winH = {}, requests = [];
  const document = {
    getElementById: (id) => byId[id] || (byId[id] = new Elem("div", id)),
    createElement: (tag) => new Elem(tag),
    addEventListener: (ev, f) => { (docH[ev] = docH[ev] || []).push(f); },
  };
  const location = {hash: hash || ""};
  const window = {addEventListener: (ev, f) => { (winH[ev] = winH[ev] || []).push(f); }, location};
  function fetch(path, opts) {
    requests.push({path, method: (opts && opts.method) || "GET"});
    let r = routes[path];
    if (typeof r === "function") r = r(path, opts);
    else if (r !== undefined) r = {status: 200, body: r};
    else r = {status: 404, body: {error: {code: "not_found", message: "no route " + path}}};
    return Promise.resolve({ok: r.status < 400, status: r.status,
                            text: () => Promise.resolve(r.body === undefined ? "" : JSON.stringify(r.body))});
  }
  const ctx = vm.createContext({document, window, location, fetch, setInterval: () => 0, clearInterval: () => {},
                                setTimeout, clearTimeout, console, JSON, Object, Array, Math, Number,
                                String, Date, isNaN, isFinite, parseFloat, encodeURIComponent,
                                decodeURIComponent, Promise, Error, RegExp});
  const script = page.slice(page.indexOf("<script>") + 8, page.indexOf("</script>"));
  vm.runInContext(script, ctx);
  return {ctx, byId, $: document.getElementById, requests, location,
          fire: (ev) => (docH[ev] || []).concat(winH[ev] || []).forEach((f) => f({}))};
}
const settle = async () => { for (let i = 0; i < 20; i++) await new Promise((r) => setTimeout(r, 0)); };

let failed = 0;
function check(cond, what) {
  if (!cond) { failed++; console.error("FAIL: " + what); }
}
function eq(a, b, what) { check(a === b, `${what}: got ${JSON.stringify(a)}, want ${JSON.stringify(b)}`); }
function deepEqual(a, b) { return JSON.stringify(a) === JSON.stringify(b); }

/* ------------------------------------------------------------------ fixtures */

const page = fs.readFileSync(process.argv[2], "utf8");
const KINDS = JSON.parse(page.slice(page.indexOf("var KINDS = ") + 12, page.indexOf(";\n", page.indexOf("var KINDS = "))));
const kinds = Object.keys(KINDS);
// the 2D kind has views with a "color" option, the 3D one a view with a "z" option (the page names neither)
const k2 = kinds.find((k) => KINDS[k].views.some((v) => v.options.includes("color")));
const k3 = kinds.find((k) => KINDS[k].views.some((v) => v.options.includes("z")));
check(k2 && k3 && k2 !== k3, "a kind with a color view and one with a z view");

const warning = "IMC stopped at max_steps: error 0.31 > threshold 0.05";
const fit = {
  cell_area: {law: "lognormal", target: {mean: 0.002, cov: 0.8}, achieved: {mean: 0.00201, cov: 0.79},
              ks: 0.021, ks_critical: 0.061, w1: 0.012, n: 500},
  grain_area: {law: "lognormal", target: {mean: 0.0013, cov: 0.8}, achieved: {mean: 0.0013, cov: 0.62},
               ks: 0.09, ks_critical: 0.061, w1: 0.05, n: 500},
  cell_orientation: {target: {mean_deg: 0, anisotropy: 1}, ks: 0.03, ks_critical: 0.061, n: 500},
  passing: {diameters: [0.01, 0.02], target: [10, 100], achieved: [13.1, 100], max_error_pp: 3.1},
};
const T0 = "2026-01-01T00:00:00Z", T1 = "2026-01-01T00:00:02Z", T2 = "2026-01-01T00:01:30Z";
function job(id, kind, status, extra) {
  const j = {id, kind, status, created_at: T0, started_at: status === "queued" ? null : T1,
             finished_at: ["succeeded", "failed", "cancelled"].includes(status) ? T2 : null,
             progress: {phase: status === "queued" ? "queued" : "done", fraction: status === "succeeded" ? 1 : 0, eta_s: null, detail: {}},
             error: null,
             brief: {particles: kind === k2 ? 500 : 1234, seed: kind === k2 ? 42 : 7,
                     headline: kind === k2 ? {name: "solid_fraction", target: 0.65, achieved: status === "succeeded" ? 0.6481 : null}
                                           : {name: "porosity", target: 0.38, achieved: status === "succeeded" ? 0.3812 : null}}};
  return Object.assign(j, extra || {});
}
const id = (n) => n.padEnd(32, "0");
const A = id("aaaa"), B = id("bbbb"), C = id("cccc"), D = id("dddd"), E = id("eeee"), W = id("ffff");
const running = job(A, k2, "running", {progress: {phase: "imc", fraction: 0.67, eta_s: 12.5, detail: {steps: 12000, error: 0.0031}}});
const cancelled = job(A, k2, "cancelled", {progress: {phase: "imc", fraction: 0.67, eta_s: null, detail: {}}});
const done2 = job(B, k2, "succeeded", {progress: {phase: "done", fraction: 1, eta_s: 0,
                                                  detail: {steps: 1000, error: 0.0019, stop_reason: "threshold", warnings: [], fit}}});
const queued = job(C, k3, "queued");
const done3 = job(D, k3, "succeeded");
const failedJob = job(E, k3, "failed", {progress: {phase: "compaction", fraction: 0.4, eta_s: null, detail: {}},
                                        error: {code: "infeasible", message: "porosity 0.2 cannot be reached (stop reason: jammed)"}});
const warned = job(W, k2, "succeeded", {progress: {phase: "done", fraction: 1, eta_s: 0,
                                                   detail: {steps: 1000, error: 0.31, stop_reason: "max_steps", warnings: [warning], fit}}});

const summary2 = {kind: k2, seed: 42, outputs: ["grains", "odec", "descriptors", "cells"],
  stats: {particles: {target: 500, achieved: 500},
          imc_error: {target: 0.002, achieved: 0.0019, measure: "E3", floor: 0.0004, stop_reason: "threshold"},
          imc_steps: {max: 1000000, achieved: 41234},
          solid_fraction: {target: 0.65, achieved: 0.6481},
          container_area: 1, cells_target_met: 487, mean_orientation_gap_deg: 3.2,
          descriptors: {elongation: {mean: 0.81, edges: [0, 1], target: null, achieved: [1]},
                        roundness: {mean: 0.62, edges: [0, 1], target: null, achieved: [1]}},
          fit},
  warnings: [], timings: {tessellation: 0.4, imc: 12.25, fill: 3.5, odec: 1.25, descriptors: 0.5, total: 17.9}};
const summary3 = {kind: k3, seed: 7, outputs: ["spheres", "fabric"], box: [2, 2, 2], sample_box: [0.5, 0.5, 0.5],
  tiling: [4, 4, 4],
  stats: {porosity: {target: 0.38, achieved: 0.3812, sample: 0.3805, deposition: 0.452},
          coordination_number: 4.87, coordination_spheres: 4.61,
          fabric: [[0.34, 0.01, 0], [0.01, 0.33, 0], [0, 0, 0.33]],
          psd: {diameters: [0.01, 0.02, 0.05], target_weight: [0, 2, 100], achieved_weight: [0, 3.5, 100],
                target_number: [0, 10, 100], target_number_midbin: [0, 10, 100], achieved_number: [0, 11, 100]},
          particles: 98765, sample_particles: 1543, contacts: 240000, wall_contacts: 900, stop_reason: "porosity",
          stability: 0.001},
  timings: {deposition: 5.5, compaction: 20, relaxation: 2, tiling: 1, total: 28.5}};
const health = {status: "ok", version: "0.9.0", uptime_s: 539.5135711179998, queue_depth: 3, running: 1,
                workers: 2, workers_busy: 1, jobs: {queued: 3, running: 1, succeeded: 10, failed: 1, cancelled: 2}};

const LIST = "/v1/jobs?limit=25";
const routes = {
  [LIST]: {jobs: [running, done2, queued, done3, failedJob, warned], next: W},
  [LIST + "&after=" + W]: {jobs: [], next: null},
  "/v1/health": health,
  [`/v1/jobs/${B}/summary`]: summary2,
  [`/v1/jobs/${D}/summary`]: summary3,
  [`/v1/jobs/${B}`]: done2,
  [`/v1/jobs/${W}/summary`]: {status: 404, body: {error: {code: "not_found", message: "no route"}}},
};
routes[`/v1/jobs/${W}/summary`] = () => ({status: 404, body: {error: {code: "not_found", message: "no such endpoint"}}});

/* ------------------------------------------------------------------ the checks */

(async () => {
  const P = boot(page, "", routes);
  const {ctx, $} = P;
  await settle();

  // the header: the service in words
  eq($("health").textContent, "up 9 min · 2 workers (1 busy) · 3 queued · 1 running", "header");

  // compact example specs
  for (const k of kinds) {
    $("kind").value = k;
    ctx.loadExample();
    const text = $("spec").value, lines = text.split("\n");
    check(deepEqual(JSON.parse(text), KINDS[k].example), `${k}: the example parses back to the same JSON`);
    check(lines.length < 20, `${k}: example in ${lines.length} lines (< 20)`);
    check(lines.every((l) => l.length <= 80), `${k}: example lines within 80 characters`);
    check(!lines.some((l) => /^\s*-?[0-9.eE+-]+,?\s*$/.test(l)), `${k}: no number alone on a line`);
  }
  // a long array is filled line by line and parses back
  const big = {kind: "x", outlines: [Array.from({length: 60}, (_, i) => [i / 7, (i * i) % 13 / 3])],
               spectrum: Array.from({length: 40}, (_, i) => 1 / (i + 1)), nested: {a: {b: [1, 2, 3], c: "d"}}};
  const bigText = ctx.compactJSON(big);
  check(deepEqual(JSON.parse(bigText), big), "compactJSON: a large spec parses back to the same JSON");
  check(bigText.split("\n").every((l) => l.length <= 100), "compactJSON: long arrays wrapped");
  check(bigText.split("\n").length < 60, "compactJSON: long arrays filled, not one item a line");

  // quick fields
  $("kind").value = k2; ctx.loadExample();
  eq($("q-particles").value, String(KINDS[k2].example.particles), "quick particles from the 2D example");
  eq($("ql-porosity").style.display, "none", "no porosity field for the 2D kind");
  eq($("ql-solid-fraction").style.display, "", "a solid fraction field for the 2D kind");
  $("q-particles").value = "200"; $("q-particles").oninput();
  $("q-seed").value = "9"; $("q-seed").oninput();
  $("q-solid-fraction").value = "0.7"; $("q-solid-fraction").oninput();
  const edited = JSON.parse($("spec").value);
  check(edited.particles === 200 && edited.seed === 9 && edited.solid_fraction === 0.7 &&
        edited.kind === k2, "quick fields edit the spec: " + JSON.stringify(edited).slice(0, 120));
  $("kind").value = k3; ctx.loadExample();
  eq($("ql-porosity").style.display, "", "a porosity field for the 3D kind");
  $("q-porosity").value = "0.4"; $("q-porosity").oninput();
  eq(JSON.parse($("spec").value).porosity, 0.4, "quick porosity edits the spec");
  $("spec").value = "{\"kind\": \"" + k3 + "\", \"porosity\": 0.41}"; $("spec").oninput();
  eq($("q-porosity").value, "0.41", "the quick field follows the spec typed");

  // grain outlines from a file: the parser (JSON or one outline a line), the file input that
  // puts them in the spec as shape.outlines, the analyse button (POST /v1/shapes/analyze)
  eq($("outlines-row").style.display, "none", "no outline file for the 3D kind");
  $("kind").value = k2; ctx.loadExample();
  eq($("outlines-row").style.display, "", "an outline file input for the 2D kind");
  const txt = "# two grains\n0 0 1 0 1 1 0 1\n\n0,0 2,0 2,2  0,2 1,3\r\n";
  const fromText = [[[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 0], [2, 0], [2, 2], [0, 2], [1, 3]]];
  check(deepEqual(ctx.parseOutlines(txt), fromText), "outline text: one a line, x y or x,y pairs, comments skipped");
  const arr = [[[0, 0], [1, 0], [0, 1]], [[5, 5], [6, 5.5], [6, 6]]];
  check(deepEqual(ctx.parseOutlines(JSON.stringify(arr)), arr), "outline JSON: an array of outlines");
  check(deepEqual(ctx.parseOutlines(JSON.stringify({outlines: arr})), arr), "outline JSON: an object with outlines");
  const throws = (t) => { try { ctx.parseOutlines(t); return ""; } catch (e) { return e.message; } };
  check(/line 2.*pairs/.test(throws("0 0 1 0 1 1\n0 0 1 0 1")), "an odd count of numbers names its line: " + throws("0 0 1 0 1 1\n0 0 1 0 1"));
  check(/line 1/.test(throws("0 0 a 1 1 1")), "a word among the numbers names its line");
  check(/without outlines/.test(throws("{\"x\": 1}")), "JSON without outlines: " + throws("{\"x\": 1}"));
  check(/outline 2/.test(throws("[[[0, 0], [1, 0], [0, 1]], [1, 2]]")), "JSON: a bad outline named");
  check(throws("# nothing\n") !== "", "an empty file is an error");
  const ex2 = KINDS[k2].example;
  $("q-outlines").files = [{name: "grains.txt", text: () => Promise.resolve(txt)}];
  await $("q-outlines").onchange(); await settle();
  const withOutl = JSON.parse($("spec").value);
  check(deepEqual(withOutl.shape, {outlines: fromText}) && withOutl.kind === k2 && withOutl.particles === ex2.particles,
        "the file's outlines are the spec's shape, the rest kept: " + JSON.stringify(withOutl).slice(0, 160));
  check($("outlines-info").textContent.startsWith("2 outlines, 9 points"), "the count shown: " + $("outlines-info").textContent);
  $("q-outlines").files = [{name: "grains.json", text: () => Promise.resolve(JSON.stringify({outlines: arr}))}];
  await $("q-outlines").onchange(); await settle();
  check(deepEqual(JSON.parse($("spec").value).shape, {outlines: arr}), "a JSON file too");
  $("q-outlines").files = [{name: "bad.txt", text: () => Promise.resolve("0 0 1")}];
  await $("q-outlines").onchange(); await settle();
  check($("analyse-msg").classes().includes("err") && $("analyse-msg").textContent.includes("bad.txt"),
        "a bad file: its name and the problem: " + $("analyse-msg").textContent);
  check(deepEqual(JSON.parse($("spec").value).shape, {outlines: arr}), "a bad file leaves the spec as it was");
  let sent = null;
  routes["/v1/shapes/analyze"] = (path, opts) => {
    sent = JSON.parse(opts.body);
    const mean = [1, 0.004, 0.1003, 0.0495].concat(Array(60).fill(0.001)); mean[8] = 0.0199;
    return {status: 200, body: {outlines: 2, analysed: 2, described: 2, modes: 64, contour_points: 128,
      spectrum: {mean, cov: Array(64).fill(0.2), sd: Array(64).fill(0.01), spread: 0.2},
      descriptors: {elongation: {mean: 0.8248, sd: 0.01}, roundness: {mean: 0.7614, sd: 0.03},
                    circularity: {mean: 0.8939, sd: 0.002}, regularity: {mean: 3.355, sd: 0.16}},
      reversed: [1], pole_moved: [], deduplicated: [], no_descriptors: [], refused: []}};
  };
  await $("analyse").onclick(); await settle();
  check(sent && deepEqual(sent.outlines, arr) && sent.contour_points === ex2.contour_points,
        "analyse posts the spec's outlines and contour_points: " + JSON.stringify(sent).slice(0, 120));
  const am = $("analyse-msg").textContent;
  check(am.includes("D2 0.1") && am.includes("D3 0.0495") && am.includes("D8 0.0199") && am.includes("elongation 0.825") &&
        am.includes("regularity 3.35") && am.includes("1 clockwise"), "the analysis shown: " + am);
  routes["/v1/shapes/analyze"] = () => ({status: 422, body: {error: {code: "invalid_spec", message: "/outlines/1: not star-shaped", pointer: "/outlines/1"}}});
  await $("analyse").onclick(); await settle();
  check($("analyse-msg").classes().includes("err") && $("analyse-msg").textContent.includes("/outlines/1"),
        "an analysis refused: code, message and pointer: " + $("analyse-msg").textContent);
  eq($("analyse").disabled, false, "the analyse button usable again");

  // submit: an error shows code, message and pointer
  routes["/v1/jobs"] = () => ({status: 422, body: {error: {code: "invalid_spec", message: "must be in (0, 1)", pointer: "/porosity"}}});
  ctx.submit();
  await settle();
  const sm = $("submit-msg").textContent;
  check(sm.includes("invalid_spec") && sm.includes("must be in (0, 1)") && sm.includes("/porosity"),
        "submit error: code, message and pointer: " + sm);

  // the job list
  const tbody = $("jobs");
  const rowOf = (jid) => tbody.children.find((r) => r.getAttribute("data-job-id") === jid) || null;
  const jobRows = () => tbody.children.filter((r) => r.classes().includes("job"));
  eq(jobRows().length, 6, "one tr.job per job");
  const rowA = rowOf(A);
  check(rowA && rowA.getAttribute("data-status") === "running", "running row with data-status");
  if (rowA) {
    const t = rowA.textContent;
    check(t.includes(k2) && t.includes("500") && t.includes("42"), "row: kind, particles, seed: " + t);
    check(t.includes("imc 67 %") && t.includes("eta 13 s"), "row: the phase, percent and ETA: " + t);
    check(rowA.find("bar")[0].classes().includes("running"), "a running job: running bar");
  }
  const rowB = rowOf(B);
  check(rowB && rowB.find("achieved")[0] && rowB.find("achieved")[0].textContent === "0.6481" &&
        rowB.textContent.includes("0.65"), "row: the headline achieved value and target");
  eq($("page-next").disabled, false, "older page button enabled (next cursor)");
  eq($("page-prev").disabled, true, "newer page button disabled on the first page");

  // a failed job: red, with its message
  const rowE = rowOf(E);
  check(rowE && rowE.find("bar")[0].classes().includes("failed") && rowE.find("s-failed").length === 1,
        "a failed job: red bar and status");
  check(rowE && rowE.textContent.includes("porosity 0.2 cannot be reached"), "a failed job: its error message in the row");

  // warnings (amber, a marker) and a clean job (green)
  const rowW = rowOf(W);
  check(rowW.find("s-warn").length === 1, "a job with warnings: amber status");
  check(rowW.find("warnmark").length === 1 && rowW.find("warnmark")[0].textContent === "⚠ 1 warning", "a job with warnings: the marker");
  eq((rowW.find("warnmark")[0] || new Elem("span")).getAttribute("title"), warning, "the marker's title is the warning");
  check(rowW.find("bar")[0].classes().includes("warn"), "a job with warnings: amber bar");
  check(rowB.find("s-warn").length === 0 && rowB.find("warnmark").length === 0 && rowB.find("s-succeeded").length === 1 &&
        !rowB.find("bar")[0].classes().includes("warn"), "a clean job: green, no marker");

  // rows updated in place: the same element after a refresh that changes the status
  routes[LIST] = {jobs: [cancelled, done2, queued, done3, failedJob, warned], next: W};
  await ctx.refresh(true); await settle();
  check(rowOf(A) === rowA, "the row of a job is the same element after a refresh");
  eq(rowA.getAttribute("data-status"), "cancelled", "data-status kept current");
  const barA = rowA.find("bar")[0];
  check(barA.classes().includes("cancelled") && !barA.classes().includes("running"), "a cancelled job: its bar is not a running bar");
  check(rowA.classes().includes("st-cancelled") && rowA.find("s-cancelled").length === 1, "a cancelled job: drawn grey");
  check(rowA.textContent.includes("cancelled at imc 67 %"), "a cancelled job says so: " + rowA.find("ptext")[0].textContent);
  eq(jobRows().length, 6, "still six rows");

  // not touched while a mouse button is down; applied on its release
  const N = id("1111"), newJob = job(N, k2, "queued");
  routes[LIST] = {jobs: [newJob, cancelled, done2, queued, done3, failedJob, warned], next: W};
  P.fire("mousedown");
  await ctx.refresh(true); await settle();
  check(!rowOf(N) && jobRows().length === 6 && tbody.children.indexOf(rowA) >= 0, "no change while the mouse is down");
  P.fire("mouseup");
  await settle();
  check(rowOf(N) && jobRows()[0] === rowOf(N) && rowOf(A) === rowA && jobRows()[1] === rowA,
        "after the release: the new job on top, the others the same elements");

  // paging
  $("page-next").onclick(); await settle();
  check(P.requests.some((r) => r.path === LIST + "&after=" + W), "older page asked with after=next");
  eq(jobRows().length, 0, "the older page is empty");
  eq($("page-prev").disabled, false, "newer page button enabled on page 2");
  $("page-prev").onclick(); await settle();
  eq(jobRows().length, 7, "back on the first page");

  // the hash selects a job; its 2D summary
  P.location.hash = "#/jobs/" + B;
  P.fire("hashchange");
  await settle();
  eq($("detail").getAttribute("data-job-id"), B, "the hash selects the job");
  check(rowOf(B).classes().includes("sel"), "its row is marked");
  const sumRows = () => $("summary-rows").children.filter((r) => r.getAttribute("data-quantity") !== null);
  const q = (name) => sumRows().find((r) => r.getAttribute("data-quantity") === name) || new Elem("tr");
  const cell = (name, cls) => q(name).children.find((c) => c.classes().includes(cls)) || new Elem("td");
  function shows(name, target, achieved) {
    if (target !== null) {
      eq(cell(name, "target").textContent, String(target), name + " target shown");
      eq(cell(name, "target").getAttribute("data-value"), String(target), name + " target value");
    }
    eq(cell(name, "achieved").textContent, String(achieved), name + " achieved shown");
  }
  shows("particles", 500, 500);
  shows("solid_fraction", 0.65, 0.6481);
  shows("imc_error", 0.002, 0.0019);
  shows("imc_steps", 1000000, 41234);
  shows("cells_target_met", 500, 487);
  shows("cell_area_mean", 0.002, 0.00201);
  shows("cell_area_cov", 0.8, 0.79);
  shows("cell_area_ks", 0.061, 0.021);
  shows("grain_area_ks", 0.061, 0.09);
  shows("cell_orientation_ks", 0.061, 0.03);
  shows("passing_max_error_pp", null, 3.1);
  shows("elongation", null, 0.81);
  eq(cell("stop_reason", "achieved").textContent, "threshold", "stop reason shown");
  check(q("grain_area_ks").classes().includes("missed") && q("cell_area_ks").classes().includes("met"),
        "a KS over its critical value marked, one within it not");
  const tim = $("timings").byAttr("data-phase");
  check(tim.length === 6 && tim[5].getAttribute("data-phase") === "total", "timings: every phase and the total");
  check(P.requests.every((r) => !r.path.endsWith("/result")), "the page never fetches /result");

  // its pictures: one button per view, the first drawn
  const views2 = KINDS[k2].views.map((v) => v.name);
  eq($("views").byAttr("data-view").map((b) => b.getAttribute("data-view")).join(","), views2.join(","), "a button per view");
  const img = $("picture");
  eq(img.getAttribute("data-view"), views2[0], "the first view drawn");
  eq(img.getAttribute("data-job-id"), B, "the picture's job");
  eq(img.getAttribute("data-state"), "loading", "loading while it loads");
  check(img.classes().includes("loading") && $("picture-state").textContent.includes("drawing"), "a loading indicator, the picture greyed");
  eq(img.getAttribute("src"), `/v1/jobs/${B}/svg?view=${views2[0]}`, "the picture's URL");
  eq($("svg-download").getAttribute("href"), img.getAttribute("src"), "the download link is the picture's URL");
  check($("svg-download").getAttribute("download").endsWith(".svg"), "the download link downloads");
  img.onload();
  eq(img.getAttribute("data-state"), "loaded", "loaded");
  $("color").checked = true; $("color").onchange();
  check(img.getAttribute("src").endsWith("&color=orientation") && img.getAttribute("data-state") === "loading",
        "the colour option re-requests the picture");
  img.onload();
  const other = $("views").one("data-view", views2[1]);
  other.onclick();
  eq(img.getAttribute("data-view"), views2[1], "a view button shows its view");
  eq(img.getAttribute("data-state"), "loading", "the new view loads");
  img.onload();
  const ex = $("exports").byAttr("data-format");
  eq(ex.map((a) => a.getAttribute("data-format")).join(","), KINDS[k2].exports.join(","), "an export link per format");
  check(ex.every((a) => a.getAttribute("href").includes("/export?format=")), "export links");

  // selecting a row sets the hash; the 3D summary, the section's z slider
  rowOf(D).onclick();
  await settle();
  eq(P.location.hash, "#/jobs/" + D, "selecting a job sets the hash");
  eq($("detail").getAttribute("data-job-id"), D, "the detail shows it");
  shows("porosity", 0.38, 0.3812);
  shows("coordination_number", null, 4.87);
  shows("particles", null, 98765);
  shows("psd_max_error_pp", null, 1.5);
  const fab = q("fabric").find("matrix")[0];
  check(fab && fab.children.length === 3 && fab.textContent.includes("0.34"), "the fabric tensor as a matrix");
  eq(cell("stop_reason", "achieved").textContent, "porosity", "3D stop reason");
  const views3 = KINDS[k3].views, zView = views3.find((v) => v.options.includes("z")).name;
  eq(img.getAttribute("data-job-id"), D, "the 3D job's picture");
  eq(img.getAttribute("data-view"), views3[0].name, "its first view");
  if (views3[0].name === zView) {
    check(img.getAttribute("src").includes("&z=1"), "the section at the middle of the box: " + img.getAttribute("src"));
    eq($("z").getAttribute("max"), "2", "the slider spans the box");
    eq($("z-row").style.display, "", "the slider shows for the section");
    img.onload();
    $("z").value = "0.5"; $("z").onchange();
    check(img.getAttribute("src").includes("&z=0.5") && img.getAttribute("data-state") === "loading",
          "moving the slider re-requests the picture: " + img.getAttribute("src"));
  }
  const nonZ = views3.find((v) => !v.options.includes("z"));
  if (nonZ) {
    $("views").one("data-view", nonZ.name).onclick();
    eq($("z-row").style.display, "none", "no slider for a view without z");
  }

  // the cancel button: for queued and running jobs only
  rowOf(C).onclick(); await settle();
  eq($("cancel").style.display, "", "cancel shown for a queued job");
  rowOf(A).onclick(); await settle();
  eq($("cancel").style.display, "none", "no cancel for a cancelled job");
  check(!$("d-result").style.display || $("d-result").style.display === "none", "no result panel for a cancelled job");
  check($("d-progress").find("bar")[0].classes().includes("cancelled"), "the detail's bar is grey for a cancelled job");
  rowOf(E).onclick(); await settle();
  check($("d-error").style.display === "" && $("d-error").textContent.includes("infeasible") &&
        $("d-error").textContent.includes("cannot be reached"), "a failed job: its error in the detail");

  // no summary from the service: the progress detail (warnings, fit) instead
  rowOf(W).onclick(); await settle();
  eq($("d-warnings").textContent, warning, "details: the warning listed");
  shows("grain_area_ks", 0.061, 0.09);
  shows("solid_fraction", 0.65, 0.6481); // from the job's brief
  eq(cell("stop_reason", "achieved").textContent, "max_steps", "the stop reason from the progress detail");
  check($("summary-msg").textContent.includes("no summary"), "says the summary is missing");

  // a fresh load with a job's hash selects it, even when it is not on the first page
  routes[LIST] = {jobs: [newJob], next: null};
  const R = boot(page, "#/jobs/" + B, routes);
  await settle();
  eq(R.$("detail").getAttribute("data-job-id"), B, "a reload with #/jobs/{id} shows that job");
  check(R.requests.some((r) => r.path === "/v1/jobs/" + B), "the job fetched alone");
  eq((R.$("summary-rows").children.find((r) => r.getAttribute("data-quantity") === "solid_fraction") || new Elem("tr"))
       .children.map((c) => c.textContent).slice(1, 3).join("|"), "0.65|0.6481", "and its summary");

  if (failed) process.exit(1);
  console.log("dashboard_check: ok");
})().catch((e) => { console.error(e); process.exit(1); });
