// dashboard_check.js -- runs the dashboard page's script (server/dashboard.html) in node against
// a small stand-in DOM, and checks what a finished 2D job looks like: a job with warnings is
// amber (status, progress bar, a marker naming the warnings), one without is green; the details
// show the warnings and the fit table, KS above its critical value marked.
// Usage: node tests/server/dashboard_check.js PAGE.html   (tests/server/test_dashboard.c runs it; exit 0 = ok)
"use strict";
const fs = require("fs");
const vm = require("vm");

class Elem {
  constructor(tag) { this.tagName = tag; this.children = []; this.attrs = {}; this.style = {}; this.text = ""; }
  setAttribute(k, v) { this.attrs[k] = String(v); }
  getAttribute(k) { return k in this.attrs ? this.attrs[k] : null; }
  appendChild(c) { this.children.push(c); return c; }
  get className() { return this.attrs["class"] || ""; }
  set className(v) { this.attrs["class"] = String(v); }
  get textContent() { return this.text + this.children.map((c) => c.textContent).join(""); }
  set textContent(v) { this.text = String(v); this.children = []; }
  html() {
    const a = Object.keys(this.attrs).map((k) => ` ${k}="${this.attrs[k]}"`).join("");
    return `<${this.tagName}${a}>${this.text}${this.children.map((c) => c.html()).join("")}</${this.tagName}>`;
  }
  // elements whose class list has cls, depth first
  find(cls, out = []) {
    if (this.className.split(" ").includes(cls)) out.push(this);
    this.children.forEach((c) => c.find(cls, out));
    return out;
  }
}

const byId = {};
const document = {
  getElementById: (id) => byId[id] || (byId[id] = new Elem("div")),
  createElement: (tag) => new Elem(tag),
};
const page = fs.readFileSync(process.argv[2], "utf8");
const script = page.slice(page.indexOf("<script>") + 8, page.indexOf("</script>"));
const ctx = vm.createContext({document, fetch: () => new Promise(() => {}), setInterval: () => 0,
                              console, JSON, Object, Array, Math, Number, String, Date, isNaN, isFinite, parseFloat});
vm.runInContext(script, ctx);

let failed = 0;
function check(cond, what) {
  if (!cond) { failed++; console.error("FAIL: " + what); }
}

const warning = "IMC stopped at max_steps: error 0.31 > threshold 0.05";
const fit = {
  cell_area: {law: "lognormal", target: {mean: 0.002, cov: 0.8}, achieved: {mean: 0.00201, cov: 0.79},
              ks: 0.021, ks_critical: 0.061, w1: 0.012, n: 500},
  grain_area: {law: "lognormal", target: {mean: 0.0013, cov: 0.8}, achieved: {mean: 0.0013, cov: 0.62},
               ks: 0.09, ks_critical: 0.061, w1: 0.05, n: 500},
  cell_orientation: {target: {mean_deg: 0, anisotropy: 1}, ks: 0.03, ks_critical: 0.061, n: 500},
  passing: {diameters: [0.01, 0.02], target: [10, 100], achieved: [13.1, 100], max_error_pp: 3.1},
};
function job(id, warnings) {
  return {id: id, kind: "fourier-voronoi-2d", status: "succeeded", created_at: "2026-01-01T00:00:00Z",
          progress: {phase: "done", fraction: 1, eta_s: 0,
                     detail: {steps: 1000, error: 0.31, stop_reason: "max_steps", warnings: warnings, fit: fit}},
          error: null};
}

ctx.renderJobs([job("warned", [warning]), job("clean", [])]);
const rows = byId["jobs"].children;
check(rows.length === 2, "two rows");
const [warned, clean] = rows;
check(warned.find("s-warn").length === 1, "a job with warnings: amber status");
check(warned.find("warnmark").length === 1 && warned.find("warnmark")[0].textContent === "⚠ 1 warning",
      "a job with warnings: the marker");
check((warned.find("warnmark")[0] || new Elem("span")).getAttribute("title") === warning, "the marker's title is the warning");
check((warned.find("bar")[0] || new Elem("div")).className.split(" ").includes("warn"), "a job with warnings: amber bar");
check(clean.find("s-warn").length === 0 && clean.find("warnmark").length === 0, "a clean job: no marker");
check(clean.find("s-succeeded").length === 1 && !(clean.find("bar")[0] || new Elem("div")).className.includes("warn"),
      "a clean job: green");

vm.runInContext('selected = "warned"', ctx);
ctx.renderDetail();
const ul = byId["d-warnings"];
check(ul.style.display === "" && ul.textContent === warning, "details: the warning listed");
const table = byId["d-fit"].children[0];
check(table && table.className === "fit", "details: the fit table");
if (table) {
  const text = table.children.map((r) => r.children.map((c) => c.textContent).join("|"));
  check(text[1] === "cells|lognormal|0.002|0.8|0.00201|0.79|0.021 / 0.061|0.012", "cells row: " + text[1]);
  check(text[2] === "grains|lognormal|0.0013|0.8|0.0013|0.62|0.09 / 0.061|0.05", "grains row: " + text[2]);
  check(text[3].startsWith("cell orientation|cosine, mean 0°, anisotropy 1") && text[3].includes("0.03 / 0.061"),
        "orientation row: " + text[3]);
  check(text[4].startsWith("passing (sieve)") && text[4].includes("3.1 pp"), "passing row: " + text[4]);
  const over = table.find("over");
  check(over.length === 1 && over[0].textContent === "0.09 / 0.061", "only the grains' KS is marked over");
}
const dl = byId["d-info"].textContent;
check(dl.includes("max_steps") && !dl.includes("ks_critical"), "detail line: stop reason, fit left to the table");

vm.runInContext('selected = "clean"', ctx);
ctx.renderDetail();
check(byId["d-warnings"].style.display === "none" && byId["d-warnings"].children.length === 0,
      "a clean job: no warnings box");
check(byId["d-fit"].children.length === 1, "a clean job: its fit table");

if (failed) process.exit(1);
console.log("dashboard_check: ok");
