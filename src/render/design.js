// The design page: slidestack design's answer (src/design.rs) computed in the browser from the
// study's data embedded in the page (#study-data, the serialized ZoneDesign of each zone), and an
// explorer of the grid's figures. Every formula below repeats the Rust one it names, with the
// same operations in the same order, so that the numbers agree to the last digit or two.
"use strict";

const DATA = JSON.parse(document.getElementById("study-data").textContent);
const ZONES = DATA.zones;
const BLOCKS = ZONES[0].grid.alpha.length;
// A building study's page: one ZONES entry per zone and frame (design.rs, frame_designs), and
// DATA.frames: each entry's label, every frame of the study, the example query.
const FRAMES = DATA.frames || null;
const NS = "http://www.w3.org/2000/svg";
const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf", "#8c564b",
  "#e377c2", "#7f7f7f", "#bcbd22"];

const val = (v) => (v === null ? NaN : v);

// Rust's `{}` of an f64 (no exponent), for the messages that repeat the command's.
function rustNum(x) {
  if (!Number.isFinite(x)) return Number.isNaN(x) ? "NaN" : (x > 0 ? "inf" : "-inf");
  const s = String(x);
  if (!/e/.test(s)) return s;
  const digits = Math.max(0, -Math.floor(Math.log10(Math.abs(x))) + 17);
  return x.toFixed(Math.min(100, digits)).replace(/0+$/, "").replace(/\.$/, "");
}

// Rust's `{:?}` of an f64: a decimal with a fraction digit from 1e-4 to 1e16, else the shortest
// digits with an exponent.
function rustDebug(x) {
  if (!Number.isFinite(x)) return rustNum(x);
  const a = Math.abs(x);
  if (a === 0 || (a >= 1e-4 && a < 1e16)) {
    const s = rustNum(x);
    return (Object.is(x, -0) ? "-" : "") + (s.includes(".") ? s : s + ".0");
  }
  const [m, e] = x.toExponential().split("e");
  return m + "e" + (e.startsWith("+") ? e.slice(1) : e);
}

// design.rs, shown: a bound rounded to 7 significant digits.
const shown = (v) => rustDebug(Number(v.toExponential(6)));

// grid.rs, Grid::interpolate: multilinear in [T_p, α_1 … α_n, μ_1 … μ_n]; `outside` names the
// first dimension out of range, `value` is null where a corner with weight has no T_new.
function interpolate(grid, values, point) {
  const axes = [grid.periods_s, ...grid.alpha, ...grid.mu];
  const n = grid.alpha.length;
  const names = ["T_p"];
  for (let i = 1; i <= n; i++) names.push("alpha_" + i);
  for (let i = 1; i <= n; i++) names.push("mu_" + i);
  const brackets = [];
  for (let d = 0; d < axes.length; d++) {
    const axis = axes[d];
    const x = point[d];
    const lo = axis[0];
    const hi = axis[axis.length - 1];
    if (!(x >= lo && x <= hi)) return { outside: { dim: names[d], value: x, lo, hi } };
    let p = 0;
    while (p < axis.length && axis[p] <= x) p++;
    const i = Math.min(Math.max(p, 1), Math.max(axis.length, 2) - 1) - 1;
    if (axis.length === 1) brackets.push([0, 0.0]);
    else brackets.push([i, (x - axis[i]) / (axis[i + 1] - axis[i])]);
  }
  const shape = axes.map((a) => a.length);
  let total = 0.0;
  for (let corner = 0; corner < 2 ** axes.length; corner++) {
    let weight = 1.0;
    let flat = 0;
    for (let d = 0; d < brackets.length; d++) {
      const [i, w] = brackets[d];
      const up = Math.floor(corner / 2 ** d) % 2 === 1;
      weight *= up ? w : 1.0 - w;
      flat = flat * shape[d] + i + (up ? 1 : 0);
    }
    if (weight === 0.0) continue;
    const v = val(values[flat]);
    if (Number.isNaN(v)) return { value: null };
    total += weight * v;
  }
  return { value: total };
}

const dot = (a, b) => {
  let s = 0.0;
  for (let i = 0; i < Math.min(a.length, b.length); i++) s += a[i] * b[i];
  return s;
};

// fit/forms.rs, logistic.
function logistic(z) {
  const e = Math.exp(-Math.abs(z));
  return z >= 0.0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
}

// fit/forms.rs, Form::regressors and Form::evaluate (no gradient).
function predict(fit, x, tP, tRigid) {
  const p = fit.params;
  if (fit.form === "fraction") {
    const z = x.map(Math.log);
    z.push(z[0] * z[0]);
    const k = z.length;
    return logistic(dot(p.slice(0, k), z) + p[k]);
  }
  if (fit.form === "paper") {
    const k = x.length;
    const ex = Math.exp(dot(p.slice(k, 2 * k), x));
    return dot(p.slice(0, k), x) + p[2 * k] * ex + p[2 * k + 1];
  }
  if (fit.form === "bounded") {
    const k = x.length;
    return tP + (tRigid - tP) * logistic(dot(p.slice(0, k), x) + p[k]);
  }
  if (fit.form === "damped") {
    const z = x.map(Math.log);
    z.push(z[0] * z[0]);
    const k = z.length;
    const span = tRigid - tP;
    const s1 = logistic(dot(p.slice(0, k), z) + p[k]);
    const s2 = logistic(dot(p.slice(k + 1, 2 * k + 1), z) + p[2 * k + 1]);
    return tP * (1.0 - DATA.damping_depth * s2) + span * s1;
  }
  throw new Error("design.js: unknown form `" + fit.form + "`: this page predates the study");
}

// fit/published.rs, PaperEquation::evaluate.
function paperEquation(eq, x) {
  if (!eq || x.length !== 5) return null;
  return dot(eq.a, x) + eq.b * Math.exp(dot(eq.c, x) + eq.d) + eq.e;
}

// spectrum/target.rs, TargetSpectrum::sa_g (Soil::sa_g, asce7_sa_g, interpolate_log_log).
function saG(t, T) {
  if (Number.isNaN(T) || T < 0.0) return NaN;
  if (t.kind === "is1893") {
    let s;
    if (T < 0.10) s = 1.0 + 15.0 * T;
    else if (T <= t.corner_s) s = 2.5;
    else if (T <= 4.0) s = t.descending_s / T;
    else s = t.long_g;
    return t.factor * (t.importance / t.response_reduction) * s;
  }
  if (t.kind === "asce7") {
    const ts = t.sd1_g / t.sds_g;
    const t0 = 0.2 * ts;
    if (T < t0) return t.sds_g * (0.4 + 0.6 * T / t0);
    if (T <= ts) return t.sds_g;
    if (T <= t.tl_s) return t.sd1_g / T;
    return t.sd1_g * t.tl_s / (T * T);
  }
  if (t.kind !== "table") {
    throw new Error("design.js: unknown target kind `" + t.kind +
      "`: this page predates the study");
  }
  const ps = t.periods_s;
  const sa = t.sa_g;
  const n = Math.min(ps.length, sa.length);
  if (n === 0) return NaN;
  if (T <= ps[0]) return sa[0];
  if (T >= ps[n - 1]) return sa[n - 1];
  let k = 0;
  while (k < n && ps[k] <= T) k++;
  const [t0, t1, s0, s1] = [ps[k - 1], ps[k], sa[k - 1], sa[k]];
  if (T === t0) return s0;
  if (t0 === 0.0) return s0 + (s1 - s0) * T / t1;
  return s0 * Math.pow(s1 / s0, Math.log(T / t0) / Math.log(t1 / t0));
}

const fin = (v) => (v !== null && Number.isFinite(v) ? v : null);

// ---- a building study's frame ----

// grid.rs, StackFloor: parsed from its text (`3`, `roof`, `mid`, `all`), and StackFloor::floors.
function parseFloor(s) {
  if (s === "roof" || s === "mid" || s === "all") return { floor: s };
  if (/^\+?[0-9]+$/.test(s) && Number(s) >= 1) return { floor: Number(s) };
  return { error: "`" + s + "` is not a floor, `roof`, `mid` or `all`" };
}

function floorsOf(floor, storeys) {
  if (floor === "roof") return [storeys];
  if (floor === "mid") return [Math.ceil(storeys / 2)];
  if (floor === "all") return Array.from({ length: storeys }, (_, i) => i + 1);
  if (typeof floor === "number") return [floor];
  throw new Error("design.js: unknown stack floor `" + floor + "`");
}

const sameList = (a, b) => a.length === b.length && a.every((v, i) => v === b[i]);

// design.rs, frame_index: the first frame of `storeys` storeys whose stacks stand on the floors
// `floor` names there (ZONES holds the first of each building), or the command's refusal.
function frameEntry(zone, storeys, floor) {
  const wanted = floorsOf(floor, storeys);
  const refuse = (known) => ({ error: "the study has no building of " + storeys +
    " storeys with the stack on floor `" + floor + "`; it has " + known });
  if (typeof floor === "number" && !(floor >= 1 && floor <= storeys)) {
    return refuse("floors 1 … " + storeys + " in a building of " + storeys + " storeys");
  }
  const k = ZONES.findIndex((z) => z.zone === zone && z.building.frame.storeys === storeys &&
    sameList(floorsOf(parseFloor(z.building.frame.stack_floor).floor, storeys), wanted));
  return k < 0 ? refuse(FRAMES.known) : { z: ZONES[k], label: FRAMES.labels[k] };
}

// study/building.rs, Frame::stack_height_ratio.
function stackHeightRatio(spec) {
  const n = spec.floor_masses.length;
  const height = (f) => {
    let h = 0.0;
    for (let i = 0; i < f; i++) h += spec.storey_heights_m[i];
    return h;
  };
  const roof = height(n);
  const floors = floorsOf(parseFloor(spec.stack_floor).floor, n);
  const weight = (f) => spec.floor_masses[f - 1];
  let total = 0.0;
  for (const f of floors) total += weight(f);
  let sum = 0.0;
  for (const f of floors) sum += weight(f) * height(f) / roof;
  return sum / total;
}

// The lowest eigenvalue of K·φ = ω²·M·φ (dynamics/building/model.rs, modes: the symmetric
// tridiagonal M^{-1/2}·K·M^{-1/2}), by bisection on its Sturm sequence to the last bit
// (a different algorithm from nalgebra's: the two agree to a few ulps of the matrix's norm).
function lowestOmega2(masses, k) {
  const n = masses.length;
  const s = masses.map((m) => 1.0 / Math.sqrt(m));
  const d = [];
  const e = [];
  for (let r = 0; r < n; r++) {
    const above = r + 1 < n ? k[r + 1] : 0.0;
    d.push(s[r] * (k[r] + above) * s[r]);
    if (r + 1 < n) e.push(s[r] * -k[r + 1] * s[r + 1]);
  }
  let lo = Infinity;
  let hi = -Infinity;
  for (let r = 0; r < n; r++) {
    const off = (r > 0 ? Math.abs(e[r - 1]) : 0.0) + (r + 1 < n ? Math.abs(e[r]) : 0.0);
    lo = Math.min(lo, d[r] - off);
    hi = Math.max(hi, d[r] + off);
  }
  // How many eigenvalues lie below x.
  const below = (x) => {
    let count = 0;
    let q = 1.0;
    for (let r = 0; r < n; r++) {
      q = d[r] - x - (r > 0 ? (e[r - 1] * e[r - 1]) / q : 0.0);
      if (q === 0.0) q = -Number.MIN_VALUE;
      if (q < 0.0) count++;
    }
    return count;
  };
  for (;;) {
    const mid = 0.5 * (lo + hi);
    if (!(mid > lo && mid < hi)) break;
    if (below(mid) >= 1) hi = mid;
    else lo = mid;
  }
  return 0.5 * (lo + hi);
}

// study/building.rs, Frame::t_rigid_s (T_p·sqrt(1+α) on one storey).
function frameTRigid(spec, period, alphaTotal) {
  const n = spec.floor_masses.length;
  if (n === 1) return period * Math.sqrt(1.0 + alphaTotal);
  const loaded = spec.floor_masses.slice();
  for (const f of floorsOf(parseFloor(spec.stack_floor).floor, n)) loaded[f - 1] *= 1.0 + alphaTotal;
  const bare = lowestOmega2(spec.floor_masses, spec.storey_stiffnesses);
  const rigid = lowestOmega2(loaded, spec.storey_stiffnesses);
  return period * Math.sqrt(bare / rigid);
}

// fit/mod.rs, BuildingFeatures::features (the one-storey features without a building or
// without its features).
function fitFeatures(z, period, alpha, mu) {
  const x = [period, ...mu, ...alpha];
  if (!z.building || !z.building.features) return x;
  const spec = z.building.frame;
  const bf = z.building.features;
  if (bf.storeys) x.push(spec.storeys);
  if (bf.height) x.push(stackHeightRatio(spec));
  return x;
}

// T_rigid (s) of entry `z` for T_p `period` and the stack's total mass ratio `alphaTotal`.
function tRigidOf(z, period, alphaTotal) {
  return z.building ? frameTRigid(z.building.frame, period, alphaTotal)
    : period * Math.sqrt(1.0 + alphaTotal);
}

// design.rs, check_extrapolation: null where the fitted form may answer at `point` (outside the
// grid, `text` saying where), else the command's refusal.
function checkExtrapolation(z, point, text) {
  const m = z.extrapolation_margin;
  if (m === null || m === undefined) {
    return text + "; no fitted form was found to stay a period of the structure beyond the grid " +
      "(fit.yaml's box check), so nothing answers there";
  }
  const g = z.grid;
  const axes = [g.periods_s, ...g.alpha, ...g.mu];
  const names = ["T_p"];
  for (let i = 1; i <= g.alpha.length; i++) names.push("alpha_" + i);
  for (let i = 1; i <= g.alpha.length; i++) names.push("mu_" + i);
  for (let d = 0; d < axes.length; d++) {
    const gridLo = Math.min(...axes[d]);
    const gridHi = Math.max(...axes[d]);
    const lo = (1.0 - m) * gridLo;
    const hi = (1.0 + m) * gridHi;
    if (!(point[d] >= lo && point[d] <= hi)) {
      return names[d] + " = " + rustDebug(point[d]) + " lies outside " + shown(lo) + " … " +
        shown(hi) + ", the study's grid (" + shown(gridLo) + " … " + shown(gridHi) + ") and " +
        (100.0 * m).toFixed(0) + " % beyond, the only range where the fitted form was checked " +
        "to stay a period of the structure (finite, T_new within " + rustNum(DATA.band[0]) +
        "·T_p … " + rustNum(DATA.band[1]) + "·T_rigid): nothing answers there";
    }
  }
  return null;
}

// design.rs, a_period: `t` if it is a period, else null with a note.
function aPeriod(t, what, notes) {
  if (t !== null && !(Number.isFinite(t) && t > 0.0)) {
    notes.push(what + " gives T_new = " + rustDebug(t) + " s here, which is no period: left out");
    return null;
  }
  return t;
}

// design.rs, answer: {answer} or {error}.
function answer(q) {
  let z = ZONES.find((z) => z.zone === q.zone);
  if (!z) {
    return { error: "zone `" + q.zone + "` is not in the study; it has " +
      [...new Set(ZONES.map((z) => z.zone))].join(", ") };
  }
  const bad = (what, v) => ({ error: what + " = " + rustNum(v) + " must be finite and > 0" });
  if (!(Number.isFinite(q.period) && q.period > 0)) return bad("T_p", q.period);
  const [pLo, pHi] = DATA.period_range_s;
  if (!(q.period >= pLo && q.period <= pHi)) {
    return { error: "T_p = " + rustDebug(q.period) + " must be within " + rustNum(pLo) + " … " +
      rustNum(pHi) + " s, the periods of a structure `simulate` runs" };
  }
  for (const [name, list] of [["alpha", q.alpha], ["mu", q.mu]]) {
    for (let i = 0; i < list.length; i++) {
      if (!(Number.isFinite(list[i]) && list[i] > 0)) return bad(name + "_" + (i + 1), list[i]);
    }
    if (list.length !== BLOCKS) {
      return { error: name + " lists " + list.length + " values but the study's stacks have " +
        BLOCKS + " blocks" };
    }
  }
  let label = null;
  if (FRAMES) {
    if (q.floorError) return { error: q.floorError };
    const f = frameEntry(q.zone, q.storeys, q.floor);
    if (f.error) return f;
    [z, label] = [f.z, f.label];
  }
  let alphaTotal = 0.0;
  for (const a of q.alpha) alphaTotal += a;
  const tRigid = tRigidOf(z, q.period, alphaTotal);
  const notes = [];
  if (FRAMES) {
    notes.push("a building: T_p is its bare first-mode period T_1, T_rigid its first-mode " +
      "period with the stacks rigidly attached, T_new the first mode's; the paper's equation is " +
      "the one-storey one, read at T_1");
  }
  const r = interpolate(z.grid, z.t_new_s, [q.period, ...q.alpha, ...q.mu]);
  let tGrid = null;
  if (r.outside) {
    const o = r.outside;
    const text = o.dim + " = " + rustNum(o.value) + " lies outside the grid's " + rustNum(o.lo) +
      " … " + rustNum(o.hi);
    if (!q.extrapolate) {
      return { error: text + "; with `extrapolate` the fitted form answers there", outside: true };
    }
    const beyond = checkExtrapolation(z, [q.period, ...q.alpha, ...q.mu], text);
    if (beyond) return { error: beyond, outside: true };
    notes.push(text + ": T_new from the fitted form");
  } else if (r.value === null) {
    notes.push("a grid point next to this structure has no T_new (no crossing of the mean " +
      "displacement spectrum): no interpolated value");
  } else {
    tGrid = r.value;
  }
  const x = [q.period, ...q.mu, ...q.alpha];
  const fitX = fitFeatures(z, q.period, q.alpha, q.mu);
  const tFit = aPeriod(z.fit ? predict(z.fit, fitX, q.period, tRigid) : null, "the fitted form",
    notes);
  let lambdaGrid = null;
  let lambdaFit = null;
  let lambdaCode = null;
  const onGrid = (values) => {
    const l = interpolate(z.grid, values, [q.period, ...q.alpha, ...q.mu]);
    return l.outside || l.value === null ? null : l.value;
  };
  if (z.lambda) {
    lambdaGrid = onGrid(z.lambda.per_case);
    lambdaFit = z.lambda.fit ? predict(z.lambda.fit, fitX, q.period, tRigid) : null;
  }
  if (z.lambda_code) lambdaCode = onGrid(z.lambda_code);
  // study/design.rs, answer: the interpolated share of rocking motions, and its note.
  const rocksShare = z.rocks_share ? onGrid(z.rocks_share) : null;
  if (rocksShare !== null && rocksShare > 0) {
    notes.push("rocking: the stack would start to rock under some of the motions (rocks_share, " +
      "interpolated from the grid cases around this structure): there the sliding-only model's " +
      "T_new and λ are outside their model (docs/model.md, \"Rocking: when a case leaves the " +
      "model\")");
  }
  const tPaper = aPeriod(paperEquation(z.paper, x), "the paper's equation", notes);
  const sa = (t) => (fin(t) === null ? null : saG(z.target, t));
  return {
    answer: {
      zone: z.zone, target: z.target.spec, fit_form: z.fit ? z.fit.form : "", building: label,
      lambda_grid: lambdaGrid, lambda_fit: lambdaFit, lambda_code_grid: lambdaCode,
      rocks_share: rocksShare,
      t_rigid_s: tRigid, t_new_grid_s: tGrid, t_new_fit_s: tFit, t_new_paper_s: tPaper,
      sa_tp_g: saG(z.target, q.period), sa_new_g: sa(tGrid !== null ? tGrid : tFit),
      sa_new_grid_g: sa(tGrid), sa_new_fit_g: sa(tFit), sa_new_paper_g: sa(tPaper), notes,
    },
  };
}

// ---- the form, the URL and the outputs ----

// The numeric outputs: the page's <output class='number'> elements (render/design.rs's rows).
const OUTPUTS = Array.from(document.querySelectorAll("output.number"), (o) => o.id);
const $ = (id) => document.getElementById(id);
const listOf = (s) => s.split(",").map((v) => (v.trim() === "" ? NaN : Number(v)));

// A building study's storey count and floor from their text: {storeys, floor} or, as the
// command's parsing would, {floorError}.
function frameQuery(storeys, floor) {
  const f = parseFloor(floor);
  const n = /^\+?[0-9]+$/.test(storeys) ? Number(storeys) : NaN;
  if (Number.isNaN(n)) {
    return { storeys: NaN, floor, floorError: "`" + storeys + "` is not a storey count" };
  }
  if (f.error) return { storeys: n, floor, floorError: f.error };
  return { storeys: n, floor: f.floor };
}

function defaultQuery() {
  if (FRAMES) return fromParams(new URLSearchParams(FRAMES.example), null);
  const z = ZONES.find((z) => z.zone === "III") || ZONES[0];
  const g = z.grid;
  const mid = (a) => a[Math.floor((a.length - 1) / 2)];
  if (BLOCKS === 2) {
    // The paper's Section 9 worked example.
    return { zone: z.zone, period: 0.7, alpha: [1, 1], mu: [0.3, 0.1], extrapolate: false };
  }
  return { zone: z.zone, period: mid(g.periods_s), alpha: g.alpha.map(mid), mu: g.mu.map(mid),
    extrapolate: false };
}

// The question of address parameters `p` over `q` (a default; null: none).
function fromParams(p, q) {
  q = q || { zone: "", period: NaN, alpha: [], mu: [], extrapolate: false };
  if (p.has("zone")) q.zone = p.get("zone");
  if (p.has("period")) q.period = p.get("period").trim() === "" ? NaN : Number(p.get("period"));
  if (p.has("alpha")) q.alpha = listOf(p.get("alpha"));
  if (p.has("mu")) q.mu = listOf(p.get("mu"));
  if (FRAMES) {
    const storeys = p.has("storeys") ? p.get("storeys").trim() : String(q.storeys);
    const floor = p.has("floor") ? p.get("floor").trim() : String(q.floor);
    delete q.floorError;
    Object.assign(q, frameQuery(storeys, floor));
  }
  q.extrapolate = ["1", "true", "yes", "on"].includes((p.get("extrapolate") || "").toLowerCase());
  return q;
}

function queryFromUrl() {
  return fromParams(new URLSearchParams(window.location.search), defaultQuery());
}

function queryString(q) {
  let s = "?zone=" + encodeURIComponent(q.zone) + "&period=" + q.period + "&alpha=" +
    q.alpha.join(",") + "&mu=" + q.mu.join(",");
  if (FRAMES) {
    s += "&storeys=" + encodeURIComponent(String(q.storeys)) + "&floor=" +
      encodeURIComponent(String(q.floor));
  }
  return q.extrapolate ? s + "&extrapolate=1" : s;
}

// Sets select `id` to `value`, adding it as an option if the page does not offer it (a storey
// count or floor of the address that the study lacks: the answer then says so).
function selectValue(id, value) {
  const sel = $(id);
  if (!Array.from(sel.options).some((o) => o.value === value)) sel.appendChild(new Option(value, value));
  sel.value = value;
}

function fillForm(q) {
  $("zone").value = q.zone;
  $("period").value = Number.isNaN(q.period) ? "" : q.period;
  for (let i = 0; i < BLOCKS; i++) {
    const a = q.alpha[i];
    const m = q.mu[i];
    $("alpha_" + (i + 1)).value = a === undefined || Number.isNaN(a) ? "" : a;
    $("mu_" + (i + 1)).value = m === undefined || Number.isNaN(m) ? "" : m;
  }
  $("extrapolate").checked = q.extrapolate;
  if (FRAMES) {
    selectValue("storeys", String(q.storeys));
    selectValue("floor", String(q.floor));
  }
}

function readForm() {
  const n = (id) => ($(id).value.trim() === "" ? NaN : Number($(id).value));
  const alpha = [];
  const mu = [];
  for (let i = 1; i <= BLOCKS; i++) {
    alpha.push(n("alpha_" + i));
    mu.push(n("mu_" + i));
  }
  const q = { zone: $("zone").value, period: n("period"), alpha, mu,
    extrapolate: $("extrapolate").checked };
  return FRAMES ? Object.assign(q, frameQuery($("storeys").value, $("floor").value)) : q;
}

function show(q) {
  const r = answer(q);
  const a = r.answer || {};
  for (const key of OUTPUTS) {
    const v = fin(a[key] === undefined ? null : a[key]);
    const el = $(key);
    el.textContent = v === null ? "–" : v.toFixed(3);
    if (v === null) el.removeAttribute("data-value");
    else el.setAttribute("data-value", String(v));
  }
  $("fit_form").textContent = a.fit_form || "–";
  if (FRAMES) $("building").textContent = a.building || "–";
  $("error").textContent = r.error || "";
  $("error").hidden = !r.error;
  const notes = $("notes");
  notes.textContent = "";
  for (const text of (a.notes || [])) {
    const li = document.createElement("li");
    li.textContent = text;
    notes.appendChild(li);
  }
  const link = queryString(q);
  $("permalink").setAttribute("href", link);
  $("permalink").textContent = "design.html" + link;
  drawCase(q, r.answer || null);
}

// ---- figures (SVG) ----

function niceTicks(lo, hi, count) {
  const raw = (hi - lo) / count;
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw) || raw;
  const ticks = [];
  for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) {
    ticks.push(Math.abs(v) < step * 1e-9 ? 0 : v);
  }
  return ticks;
}

function el(name, attrs, text) {
  const e = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

// A line chart into the <figure> `figId`: series {label, x, y, colour, dash, width, points}.
function chart(figId, title, xLabel, yLabel, series) {
  const fig = $(figId);
  const W = 640;
  const H = 400;
  const m = { l: 64, r: 14, t: 30, b: 48 };
  let xs = [];
  let ys = [];
  for (const s of series) {
    s.x.forEach((x, i) => {
      if (Number.isFinite(x) && Number.isFinite(s.y[i])) {
        xs.push(x);
        ys.push(s.y[i]);
      }
    });
  }
  if (xs.length === 0) {
    xs = [0, 1];
    ys = [0, 1];
  }
  let [x0, x1] = [Math.min(...xs), Math.max(...xs)];
  let [y0, y1] = [Math.min(...ys), Math.max(...ys)];
  if (x1 === x0) x1 = x0 + 1;
  if (y1 === y0) y1 = y0 + 1;
  const px = (x1 - x0) * 0.03;
  const py = (y1 - y0) * 0.06;
  [x0, x1, y0, y1] = [x0 - px, x1 + px, y0 - py, y1 + py];
  const X = (x) => m.l + ((x - x0) / (x1 - x0)) * (W - m.l - m.r);
  const Y = (y) => H - m.b - ((y - y0) / (y1 - y0)) * (H - m.t - m.b);
  const svg = el("svg", { viewBox: "0 0 " + W + " " + H, role: "img", "aria-label": title });
  svg.appendChild(el("text", { x: W / 2, y: 18, "text-anchor": "middle", class: "title" }, title));
  for (const t of niceTicks(x0, x1, 8)) {
    svg.appendChild(el("line", { x1: X(t), x2: X(t), y1: m.t, y2: H - m.b, class: "grid" }));
    svg.appendChild(el("text", { x: X(t), y: H - m.b + 16, "text-anchor": "middle" },
      String(+t.toPrecision(6))));
  }
  for (const t of niceTicks(y0, y1, 6)) {
    svg.appendChild(el("line", { x1: m.l, x2: W - m.r, y1: Y(t), y2: Y(t), class: "grid" }));
    svg.appendChild(el("text", { x: m.l - 6, y: Y(t) + 4, "text-anchor": "end" },
      String(+t.toPrecision(6))));
  }
  svg.appendChild(el("rect", { x: m.l, y: m.t, width: W - m.l - m.r, height: H - m.t - m.b,
    class: "frame" }));
  svg.appendChild(el("text", { x: (m.l + W - m.r) / 2, y: H - 8, "text-anchor": "middle" },
    xLabel));
  svg.appendChild(el("text", { x: 14, y: (m.t + H - m.b) / 2, "text-anchor": "middle",
    transform: "rotate(-90 14 " + (m.t + H - m.b) / 2 + ")" }, yLabel));
  const legend = document.createElement("ul");
  legend.className = "legend";
  for (const s of series) {
    const style = { stroke: s.colour, "stroke-width": s.width || 2, fill: "none" };
    if (s.dash) style["stroke-dasharray"] = s.dash;
    if (!s.points) {
      let d = "";
      let pen = false;
      s.x.forEach((x, i) => {
        const y = s.y[i];
        if (Number.isFinite(x) && Number.isFinite(y)) {
          d += (pen ? "L" : "M") + X(x).toFixed(1) + " " + Y(y).toFixed(1);
          pen = true;
        } else {
          pen = false;
        }
      });
      if (d) svg.appendChild(el("path", Object.assign({ d }, style)));
    } else {
      s.x.forEach((x, i) => {
        if (Number.isFinite(x) && Number.isFinite(s.y[i])) {
          svg.appendChild(el("circle", { cx: X(x), cy: Y(s.y[i]), r: 6, fill: s.fill || s.colour,
            stroke: s.colour, "stroke-width": 2 }));
        }
      });
    }
    if (s.label) {
      const li = document.createElement("li");
      const key = document.createElement("span");
      key.className = "key";
      key.style.borderColor = s.colour;
      key.style.borderStyle = s.points ? "solid" : (s.dash ? "dashed" : "solid");
      if (s.points) {
        key.classList.add("dot");
        key.style.background = s.fill || s.colour;
      }
      li.append(key, s.label);
      legend.appendChild(li);
    }
  }
  fig.textContent = "";
  fig.append(svg, legend);
}

function range(lo, hi, n) {
  return Array.from({ length: n }, (_, i) => lo + ((hi - lo) * i) / (n - 1));
}

// The period axis and the bare system's line: a building's first-mode period T_1.
function periodName() {
  return FRAMES ? "T_1" : "T_p";
}

function bareLabel() {
  return FRAMES ? "T_1 (bare building)" : "T_p (bare structure)";
}

function drawCase(q, a) {
  const f = FRAMES && a !== null ? frameEntry(q.zone, q.storeys, q.floor) : {};
  const z = f.z || ZONES.find((z) => z.zone === q.zone) || ZONES[0];
  const g = z.grid;
  const ok = a !== null;
  // T_rigid/T_p: one value for every T_p of the building (Frame::t_rigid_s scales with it).
  const root = !ok ? NaN
    : FRAMES ? a.t_rigid_s / q.period : Math.sqrt(1 + q.alpha.reduce((s, v) => s + v, 0));
  const tLo = Math.min(g.periods_s[0], ok ? q.period : Infinity);
  const tHi = Math.max(g.periods_s[g.periods_s.length - 1], ok ? q.period : -Infinity);
  const ts = range(tLo, tHi, 80);
  const series = [
    { label: bareLabel(), x: [tLo, tHi], y: [tLo, tHi], colour: "#000", width: 1 },
  ];
  if (ok) {
    series.push({ label: "T_rigid (load rigidly attached)", x: [tLo, tHi],
      y: [tLo * root, tHi * root], colour: "#000", width: 1, dash: "6 4" });
    const gridLine = g.periods_s.map((t) => {
      const r = interpolate(g, z.t_new_s, [t, ...q.alpha, ...q.mu]);
      return r.value === undefined || r.value === null ? NaN : r.value;
    });
    series.push({ label: "T_new, the study's grid (this stack)", x: g.periods_s, y: gridLine,
      colour: COLOURS[0] });
    if (z.fit) {
      series.push({ label: "T_new, fitted (" + z.fit.form + " form)", x: ts,
        y: ts.map((t) => predict(z.fit, fitFeatures(z, t, q.alpha, q.mu), t, t * root)),
        colour: COLOURS[1], dash: "8 4" });
    }
    if (z.paper && BLOCKS === 2) {
      series.push({ label: "T_new, the paper's Eqs. 16–17", x: ts,
        y: ts.map((t) => paperEquation(z.paper, [t, ...q.mu, ...q.alpha])), colour: COLOURS[2],
        dash: "2 3" });
    }
    const marks = [["t_new_grid_s", COLOURS[0], "this structure: grid"],
      ["t_new_fit_s", COLOURS[1], "this structure: fit"],
      ["t_new_paper_s", COLOURS[2], "this structure: Eqs. 16–17"]];
    for (const [key, colour, label] of marks) {
      if (fin(a[key]) !== null) {
        series.push({ label, x: [q.period], y: [a[key]], colour, points: true,
          fill: key === "t_new_grid_s" ? colour : "#fff" });
      }
    }
  }
  chart("fig-case", "Zone " + z.zone + ": T_new against " + periodName(), periodName() + " (s)",
    "T_new (s)", series);

  const top = Math.max(4, ok ? 1.1 * Math.max(q.period, fin(a.t_new_fit_s) || 0,
    fin(a.t_new_grid_s) || 0) : 0);
  const tt = range(0, top, 401);
  const spec = [{ label: z.target.label, x: tt, y: tt.map((t) => saG(z.target, t)),
    colour: "#444" }];
  if (ok) {
    spec.push({ label: "at " + periodName(), x: [q.period], y: [a.sa_tp_g], colour: "#000", points: true,
      fill: "#fff" });
    const tNew = fin(a.t_new_grid_s) !== null ? a.t_new_grid_s : a.t_new_fit_s;
    if (fin(a.sa_new_g) !== null) {
      spec.push({ label: "at T_new (" + (fin(a.t_new_grid_s) !== null ? "grid" : "fit") + ")",
        x: [tNew], y: [a.sa_new_g], colour: COLOURS[0], points: true });
    }
  }
  chart("fig-spectrum", "Zone " + z.zone + ": design spectrum", "T (s)", "Sa (g)", spec);
}

// ---- the explorer of the grid's figures ----

// The explorer's ZONES entry: its zone's, in a building study its zone and frame's.
function explorerIndex() {
  const k = FRAMES ? Number($("x-frame").value) : 0;
  const of = ZONES.map((z, i) => i).filter((i) => ZONES[i].zone === $("x-zone").value);
  return of.length > k ? of[k] : 0;
}

function explorerZone() {
  return ZONES[explorerIndex()];
}

// Flat case index within a work unit (report/select.rs, case_index).
function caseIndex(g, alphaIdx, muIdx) {
  const lens = [...g.alpha.map((a) => a.length), ...g.mu.map((a) => a.length)];
  return [...alphaIdx, ...muIdx].reduce((idx, i, d) => idx * lens[d] + i, 0);
}

function drawExplorer() {
  const z = explorerZone();
  const g = z.grid;
  const drr = DATA.drr[explorerIndex()];
  const what = $("x-quantity").value;
  const alphaIdx = g.alpha.map((_, i) => Number($("x-alpha_" + (i + 1)).value));
  const muPairs = Array.from($("x-mu").selectedOptions).map((o) => o.value.split(",").map(Number));
  const per = [...g.alpha, ...g.mu].reduce((p, a) => p * a.length, 1);
  const column = (values, c) => g.periods_s.map((_, t) => val(values[t * per + c]));
  const tp = g.periods_s;
  const series = [];
  const values = what === "T_new" ? z.t_new_s : drr[what.toLowerCase()];
  if (what === "T_new") {
    const alphaTotal = alphaIdx.reduce((s, i, b) => s + g.alpha[b][i], 0);
    const root = FRAMES ? tRigidOf(z, 1.0, alphaTotal) : Math.sqrt(1 + alphaTotal);
    series.push({ label: bareLabel(), x: tp, y: tp, colour: "#000", width: 1 });
    series.push({ label: "T_rigid (load rigidly attached)", x: tp, y: tp.map((t) => t * root),
      colour: "#000", width: 1, dash: "6 4" });
  } else {
    series.push({ label: "DRR = 1 (nothing slides)", x: [tp[0], tp[tp.length - 1]], y: [1, 1],
      colour: "#000", width: 1, dash: "2 3" });
  }
  const dashes = [null, "8 4", "2 3", "10 3 2 3"];
  muPairs.forEach((m, k) => {
    const label = m.map((i, b) => "μ_" + (b + 1) + " = " + g.mu[b][i]).join(", ");
    series.push({ label, x: tp, y: column(values, caseIndex(g, alphaIdx, m)),
      colour: COLOURS[k % COLOURS.length], dash: dashes[Math.floor(k / COLOURS.length) % 4] });
  });
  const alphaText = alphaIdx.map((i, b) => "α_" + (b + 1) + " = " + g.alpha[b][i]).join(", ");
  const yLabel = what === "T_new" ? "T_new (s)" : what + " (–)";
  chart("fig-explorer", "Zone " + z.zone + ": " + what + " against " + periodName() + ", " +
    alphaText, periodName() + " (s)", yLabel, series);
}

function explorerAxes() {
  const g = explorerZone().grid;
  for (let b = 0; b < BLOCKS; b++) {
    const sel = $("x-alpha_" + (b + 1));
    const keep = sel.value;
    sel.textContent = "";
    g.alpha[b].forEach((a, i) => sel.appendChild(new Option(String(a), String(i))));
    sel.value = keep && Number(keep) < g.alpha[b].length ? keep : String(g.alpha[b].length - 1);
  }
  const mu = $("x-mu");
  const chosen = new Set(Array.from(mu.selectedOptions).map((o) => o.value));
  mu.textContent = "";
  let combos = [[]];
  for (const axis of g.mu) {
    combos = combos.flatMap((c) => axis.map((_, i) => [...c, i]));
  }
  const first = chosen.size === 0;
  const step = Math.max(1, Math.ceil(combos.length / 6));
  combos.forEach((c, k) => {
    const text = c.map((i, b) => "μ_" + (b + 1) + " = " + g.mu[b][i]).join(", ");
    const o = new Option(text, c.join(","));
    o.selected = first ? k % step === 0 : chosen.has(o.value);
    mu.appendChild(o);
  });
  mu.size = Math.min(10, combos.length);
}

function start() {
  const q = queryFromUrl();
  fillForm(q);
  show(q);
  const update = () => {
    const q = readForm();
    show(q);
    try {
      history.replaceState(null, "", queryString(q));
    } catch (e) {
      // A browser that refuses to change a file: URL keeps the link below up to date instead.
    }
  };
  $("design").addEventListener("input", update);
  $("design").addEventListener("change", update);
  $("design").addEventListener("submit", (e) => {
    e.preventDefault();
    update();
  });
  explorerAxes();
  drawExplorer();
  for (const id of FRAMES ? ["x-zone", "x-frame"] : ["x-zone"]) {
    $(id).addEventListener("change", () => {
      explorerAxes();
      drawExplorer();
    });
  }
  $("explorer").addEventListener("change", drawExplorer);
}

start();
