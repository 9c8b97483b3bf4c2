// transfertwin console: plain JS, no build step, nothing loaded from outside the console.
"use strict";

const params = new URLSearchParams(location.search);
if (params.has("token")) {
  sessionStorage.setItem("tt_token", params.get("token"));
  params.delete("token");
  history.replaceState(null, "", location.pathname + (params.toString() ? "?" + params : ""));
}
const token = () => sessionStorage.getItem("tt_token") ||
  [...document.querySelectorAll(".token-input")].map((i) => i.value).find((v) => v) || "";
const $ = (id) => document.getElementById(id);
const el = (tag, attrs = {}, ...children) => {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v; else if (k === "text") e.textContent = v; else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
};
const fmt = (v) => (typeof v === "number" && !Number.isInteger(v) ? v.toFixed(3) : String(v));

async function api(path, options = {}) {
  const res = await fetch(path, { credentials: "same-origin", ...options });
  let body = null;
  try { body = await res.json(); } catch (e) { body = { error: res.statusText }; }
  if (!res.ok) throw new Error(body && body.error ? body.error : res.statusText);
  return body;
}

// -- tabs --------------------------------------------------------------------------------
for (const b of document.querySelectorAll("nav .tab")) {
  b.addEventListener("click", () => {
    for (const o of document.querySelectorAll("nav .tab")) o.classList.toggle("active", o === b);
    for (const p of document.querySelectorAll(".panel")) p.hidden = p.id !== "tab-" + b.dataset.tab;
    if (b.dataset.tab === "studies") { drawMap(); drawAnalysis(); }
    if (b.dataset.tab === "calibration") drawCalibration();
  });
}
if (sessionStorage.getItem("tt_token")) for (const l of document.querySelectorAll(".token-label")) l.hidden = true;
const pct = (v) => v == null ? "–" : (100 * v).toFixed(1) + " %";
const tabShown = (name) => !$("tab-" + name).hidden;

// -- assets and live values --------------------------------------------------------------
let assetIds = [];
async function loadAssets() {
  let data;
  try { data = await api("/api/assets"); } catch (e) { return; }
  showFloorError(data.kg_error);
  const tbody = document.querySelector("#assets tbody");
  const ids = data.assets.map((a) => a.id);
  if (ids.join() !== assetIds.join()) {
    tbody.replaceChildren();
    for (const a of data.assets) {
      const tr = el("tr", { class: "selectable", id: "asset-" + a.id, "data-id": a.id });
      for (const c of ["id", "class", "kind", "type", "capabilities", "status", "state", "reachable", "endpoint", "live"]) {
        tr.append(el("td", { class: "c-" + c }));
      }
      tr.addEventListener("click", () => showAas(a.id));
      tbody.append(tr);
    }
    assetIds = ids;
    fillOrderForm(data);
  }
  for (const a of data.assets) {
    const tr = $("asset-" + a.id);
    const set = (c, v) => { tr.querySelector(".c-" + c).textContent = v == null ? "" : v; };
    set("id", a.id); set("class", a.class); set("kind", a.kind); set("type", a.type || "");
    set("capabilities", a.capabilities.join(", ")); set("status", a.status);
    set("state", a.state || ""); set("endpoint", a.endpoint);
  }
}

function showFloorError(text) {
  $("kg-error").hidden = !text;
  $("kg-error").textContent = text || "";
}

// where each object lies (its PossessedBy, from the live feed): the order form's default
// target is a unit other than the one the object lies on, so the default is a valid order
const placeOf = {};
function fillOrderForm(data) {
  const fill = (sel, values, keep) => {
    const s = $(sel);
    const head = keep ? [...s.options].slice(0, 1) : [];
    s.replaceChildren(...head, ...values.map((v) => el("option", { value: v, text: v })));
  };
  fill("order-object", data.objects, false);
  fill("order-source", data.units, true);
  fill("order-target", [...data.units, ...(data.groups || [])], false);
  defaultTarget();
}
let targetChosen = false;
function defaultTarget() {
  if (targetChosen) return;
  const here = placeOf[$("order-object").value];
  const target = $("order-target");
  const other = [...target.options].find((o) => o.value !== here);
  if (other && target.value === here) target.value = other.value;
}
$("order-object").addEventListener("change", () => { targetChosen = false; defaultTarget(); });
$("order-target").addEventListener("change", () => { targetChosen = true; });

// the AAS panel is read again every few seconds while it is open, with its read time: an
// asset that went offline shows offline, not its last values
let aasShown = null, aasTimer = null;
async function showAas(id) {
  const fresh = aasShown !== id;
  aasShown = id;
  $("aas").hidden = false;
  $("aas-id").textContent = id;
  const body = $("aas-body");
  if (fresh) {
    body.replaceChildren(el("p", { class: "muted", text: "reading over OPC UA ..." }));
    $("aas-read").textContent = "";
  }
  const open = new Set([...body.querySelectorAll("details[open]")].map((d) => d.dataset.submodel));
  clearTimeout(aasTimer);
  aasTimer = setTimeout(() => { if (aasShown === id && !$("aas").hidden) showAas(id); }, 3000);
  try {
    const data = await api("/api/assets/" + encodeURIComponent(id) + "/aas");
    if (aasShown !== id) return;
    body.replaceChildren();
    $("aas").dataset.state = "online";
    $("aas-read").textContent = "read over OPC UA at " + new Date(data.read_utc).toLocaleTimeString() +
      " (wall clock); read again every 3 s";
    // the same shell for any AAS client: the floor's AAS HTTP API (IDTA-01002 Part 2)
    const apiUrl = data.aas_api ? location.origin + data.aas_api : null;
    $("aas-api").replaceChildren(...(apiUrl ? ["AAS HTTP API (IDTA Part 2, read-only): ",
      el("a", { href: apiUrl, text: apiUrl })] : []));
    for (const sm of data.submodels) {
      const table = el("table", {}, el("tr", {}, el("th", { text: "element" }), el("th", { text: "kind" }), el("th", { text: "value" })));
      for (const e of sm.elements) {
        table.append(el("tr", {}, el("td", { text: e.id_short }), el("td", { text: e.kind }),
          el("td", { text: "text" in e ? e.text : "value" in e ? fmt(e.value) : "" })));
      }
      const d = el("details", { class: "submodel", "data-submodel": sm.id_short },
        el("summary", { text: sm.id_short + " (" + sm.elements.length + ")" }), table);
      if (open.has(sm.id_short)) d.open = true;
      body.append(d);
    }
  } catch (e) {
    if (aasShown !== id) return;
    $("aas").dataset.state = "offline";
    $("aas-read").textContent = "tried at " + new Date().toLocaleTimeString() + " (wall clock)";
    body.replaceChildren(el("p", { class: "error", text: e.message }));
  }
}

// the query box: a read-only SPARQL SELECT to the knowledge graph, its rows as a table
$("query-form").addEventListener("submit", async (ev) => {
  ev.preventDefault();
  const out = $("query-result");
  out.replaceChildren(el("p", { class: "muted", text: "asking the knowledge graph ..." }));
  try {
    const data = await api("/api/query?q=" + encodeURIComponent($("query-text").value));
    const cols = [...new Set(data.rows.flatMap((r) => Object.keys(r)))];
    const table = el("table", { id: "query-table" }, el("tr", {}, ...cols.map((c) => el("th", { text: c }))));
    for (const r of data.rows) table.append(el("tr", {}, ...cols.map((c) => el("td", { text: r[c] ?? "" }))));
    out.replaceChildren(el("p", { class: "muted", text: data.rows.length + " solution(s)" }), table);
  } catch (e) {
    out.replaceChildren(el("p", { class: "error", text: e.message }));
  }
});

let events = 0;
function connectLive() {
  const source = new EventSource("/api/live");
  source.addEventListener("live", (ev) => {
    const data = JSON.parse(ev.data);
    events += 1;
    $("live-status").textContent = "live: " + events + " updates, " + new Date().toLocaleTimeString();
    showFloorError(data.kg_error);
    const stale = new Set(data.stale || []);
    for (const [id, online] of Object.entries(data.online)) {
      const tr = $("asset-" + id);
      if (!tr) { loadAssets(); continue; }  // an asset joined: its row comes with the list
      const cell = tr.querySelector(".c-reachable");
      const reason = (data.reason || {})[id];
      cell.textContent = online ? "online" : "offline" + (reason ? ": " + reason : "");
      cell.className = "c-reachable " + (online ? "on" : "off");
      tr.dataset.online = online ? "yes" : "no";
      const vals = data.values[id] || {};
      if ("PossessedBy" in vals) placeOf[id] = vals.PossessedBy;
      const shown = (data.display || {})[id] || Object.entries(vals).map(([k, v]) => [k, fmt(v)]);
      const text = shown.map(([k, v]) => k + ": " + v).join(" · ");
      const seen = (data.seen || {})[id];
      tr.querySelector(".c-live").replaceChildren(stale.has(id)
        ? el("span", { class: "live stale", text: "stale (last read " +
            (seen ? new Date(1000 * seen).toLocaleTimeString() : "?") + "): " + text })
        : el("span", { class: "live", text: text }));
    }
    renderOrders(data.orders);
    renderKpis(data.kpis);
    defaultTarget();
  });
  source.onerror = () => { $("live-status").textContent = "live: reconnecting ..."; };
}

// -- orders --------------------------------------------------------------------------------
function renderKpis(k) {
  // the TMS's KPIs (process floors): what a shift supervisor reads first
  const p = $("kpis");
  p.hidden = !k;
  if (!k) return;
  const pct = (v) => v == null ? "n/a" : (100 * v).toFixed(1) + " %";
  const [lo, hi] = k.success_share_ci95 || [null, null];
  const util = (u) => Object.entries(u).map(([a, v]) => a + " " + pct(v)).join(", ");
  const failed = Object.entries(k.failed_by_reason || {}).map(([r, n]) => r + ": " + n).join(", ");
  // a fault (a module lost mid-operation, an error) is no transfer outcome: apart, outside the share
  const faults = Object.entries(k.faults_by_reason || {}).map(([r, n]) => r + ": " + n).join(", ");
  p.replaceChildren(
    el("span", { text: "policy " + k.policy + " · " + k.orders + " orders, " + k.delivered +
      " delivered, " + k.failed + " failed, " + (k.faults || 0) + " faults, " + k.in_progress +
      " in progress" }), el("br"),
    el("span", { id: "kpi-share", text: "success share " + pct(k.success_share) +
      (lo == null ? "" : " [" + pct(lo) + ", " + pct(hi) + "] (Clopper–Pearson 95 %)") +
      " · " + k.operations_per_hour.toFixed(1) + " operations/h · mean lead time " +
      (k.mean_lead_time_s == null ? "n/a" : k.mean_lead_time_s.toFixed(1) + " s") }), el("br"),
    el("span", { text: "modules: " + util(k.utilisation.modules) + " · units: " +
      util(k.utilisation.units) + (failed ? " · failed: " + failed : "") +
      (faults ? " · faults (not in the share): " + faults : "") }));
}

function renderOrders(orders) {
  const tbody = document.querySelector("#orders tbody");
  tbody.replaceChildren(...orders.slice().reverse().map((o) => {
    // one row per operation id (unique on the floor), placed here or from the command line
    // steps are stamped with the wall clock; an "expected … s" in them is modelled floor time
    const when = (t) => (typeof t === "number" ? new Date(1000 * t).toLocaleTimeString() + " " : "");
    const steps = el("ol", { class: "steps" }, ...o.steps.map((s) => el("li", { text: when(s.t) + s.text })));
    const tr = el("tr", { id: "order-" + o.id, "data-state": o.state, "data-operation": o.operation || "",
      "data-placed-by": o.placed_by || "console" });
    const by = o.placed_by === "console" ? o.id : "command line";
    for (const v of [by, o.operation || "", o.object, o.source, o.target, o.state, o.outcome || ""]) {
      tr.append(el("td", { text: v }));
    }
    tr.children[6].className = "outcome";
    tr.append(el("td", {}, steps));
    return tr;
  }));
}

$("order-form").addEventListener("submit", async (ev) => {
  ev.preventDefault();
  const msg = $("order-message");
  const form = new FormData(ev.target);
  const body = { object: form.get("object"), target: form.get("target") };
  if (form.get("source")) body.source = form.get("source");
  msg.className = ""; msg.textContent = "submitting ...";
  try {
    const o = await api("/api/orders", { method: "POST", headers: {
      "Content-Type": "application/json", Authorization: "Bearer " + token() },
      body: JSON.stringify(body) });
    msg.className = "ok";
    msg.textContent = "order " + o.id + " placed (" + o.operation + ")";
  } catch (e) {
    msg.className = "error";
    msg.textContent = e.message;
  }
});

// -- studies -------------------------------------------------------------------------------
const dur = (s) => s == null ? "" : s < 90 ? Math.round(s) + " s" : s < 5400 ? (s / 60).toFixed(1) + " min" : (s / 3600).toFixed(1) + " h";
let studyObjects = {};
async function loadStudies() {
  let data;
  try { data = await api("/api/studies"); } catch (e) { return; }
  $("no-studies").hidden = data.studies.length > 0;
  const tbody = document.querySelector("#studies tbody");
  tbody.replaceChildren(...data.studies.map((s) => {
    const frac = s.fraction == null ? 0 : s.fraction;
    const bar = el("div", { class: "bar" }, el("div", { style: "width:" + (100 * frac).toFixed(1) + "%" }));
    const base = "/api/studies/" + encodeURIComponent(s.name) + "/results.";
    return el("tr", { id: "study-" + s.name },
      el("td", { text: s.name }), el("td", { text: s.plan || "" }),
      el("td", { class: "done", text: s.done + " / " + (s.planned == null ? "?" : s.planned) }),
      el("td", {}, bar), el("td", { text: s.rate_per_s == null ? "" : s.rate_per_s.toFixed(2) + " exp/s" }),
      el("td", { text: s.idle_s != null && s.idle_s > 300 && s.eta_s ? "idle for " + dur(s.idle_s) : dur(s.eta_s) }),
      el("td", { text: Object.entries(s.by_status).map(([k, v]) => k + " " + v).join(", ") }),
      el("td", {}, el("a", { href: base + "csv", download: "", text: "CSV" }), " ",
        el("a", { href: base + "parquet", download: "", text: "Parquet" })));
  }));
  const sel = $("map-study");
  const names = data.studies.map((s) => s.name);
  if ([...sel.options].map((o) => o.value).join() !== names.join()) {
    sel.replaceChildren(...names.map((n) => el("option", { value: n, text: n })));
  }
  const changed = {};
  for (const s of data.studies) changed[s.name] = (studyObjects[s.name] || []).join() !== s.objects.join() || studyDone[s.name] !== s.done;
  for (const s of data.studies) { studyObjects[s.name] = s.objects; studyDone[s.name] = s.done; }
  fillObjects();
  if (changed[sel.value] && !$("tab-studies").hidden) { drawMap(); drawAnalysis(); }
}
const studyDone = {};

function fillObjects() {
  const objs = studyObjects[$("map-study").value] || [];
  const sel = $("map-object");
  if ([...sel.options].map((o) => o.value).join() !== objs.join()) {
    const keep = sel.value;
    sel.replaceChildren(...objs.map((o) => el("option", { value: o, text: o })));
    if (objs.includes(keep)) sel.value = keep;
  }
}
$("map-study").addEventListener("change", () => { fillObjects(); drawMap(); drawAnalysis(); });
$("map-object").addEventListener("change", () => { drawMap(); drawAnalysis(); });

const SYMBOL = { left: "triangle-up", both: "circle", right: "triangle-down" };
// The 3-D replay of one experiment of a study (run r of a state): /replay (replay.js).
const replayUrl = (study, obj, s, run = 0) => "/replay?" + new URLSearchParams({ study,
  object: obj, face: s.face, conveyor: s.conveyor, theta: s.theta_deg, run });
// θ is signed, -179..180 (as in the tables and the report): ticks every 30°, 210° reads -150°.
const YAW_TICKS = Array.from({ length: 12 }, (_, i) => 30 * i);
async function drawMap() {
  const name = $("map-study").value, obj = $("map-object").value;
  if (!name || !obj || typeof Plotly === "undefined") return;
  let data;
  try { data = await api("/api/studies/" + encodeURIComponent(name) + "/map"); } catch (e) { return; }
  const faces = data.faces, perFace = data.objects[obj] || {};
  const traces = [];
  const layout = { height: 460, margin: { t: 50, b: 30, l: 30, r: 30 }, showlegend: true,
    legend: { orientation: "h", y: -0.05 }, annotations: [],
    title: { text: obj + ": success share per pre-transfer state (" + name + ")", font: { size: 14 } } };
  faces.forEach((face, i) => {
    const key = i === 0 ? "polar" : "polar" + (i + 1);
    const w = 1 / faces.length;
    layout[key] = { domain: { x: [i * w + 0.03, (i + 1) * w - 0.03], y: [0, 0.92] },
      angularaxis: { rotation: 90, direction: "counterclockwise", tickmode: "array",
        tickvals: YAW_TICKS, ticktext: YAW_TICKS.map((a) => (a <= 180 ? a : a - 360) + "°") },
      radialaxis: { range: [0, 1.1], showticklabels: false, ticks: "" } };
    layout.annotations.push({ text: face, showarrow: false, xref: "paper", yref: "paper",
      x: (i + 0.5) * w - 0.12, y: 1.0, font: { size: 13 } });
    traces.push({ type: "scatterpolar", subplot: key, r: [], theta: [], showlegend: false,
      hoverinfo: "skip" });  // draws the face's axes even before it has results
    for (const conveyor of ["left", "both", "right"]) {
      const pts = (perFace[face] || []).filter((p) => p.conveyor === conveyor);
      if (!pts.length) continue;
      traces.push({ type: "scatterpolar", mode: "markers", subplot: key,
        name: face + " / " + conveyor, r: pts.map((p) => p.r), theta: pts.map((p) => p.theta_deg),
        customdata: pts.map((p) => [conveyor, p.n, p.successes, p.share, face, p.theta_deg]),
        marker: { size: 10, symbol: SYMBOL[conveyor], color: pts.map((p) => p.share),
          cmin: 0, cmax: 1, colorscale: [[0, "#cf222e"], [0.5, "#e3b341"], [1, "#1a7f37"]],
          showscale: !traces.some((t) => t.marker && t.marker.showscale), colorbar: { title: { text: "success" }, len: 0.6 },
          line: { width: 0.5, color: "#333" } },
        hovertemplate: obj + " %{customdata[4]}, θ = %{theta}, conveyor %{customdata[0]}<br>" +
          "success %{customdata[2]} of %{customdata[1]} (%{customdata[3]:.0%})<br>" +
          "click: replay run 0 in 3-D<extra></extra>" });
    }
  });
  Plotly.react("polar", traces, layout, { displaylogo: false, responsive: true });
  const polar = $("polar");
  if (!polar.dataset.replayClick) {  // a state's point opens its replay
    polar.dataset.replayClick = "1";
    polar.on("plotly_click", (ev) => {
      const c = ev.points && ev.points[0] && ev.points[0].customdata;
      if (!c) return;
      window.open(replayUrl($("map-study").value, $("map-object").value,
        { face: c[4], conveyor: c[0], theta_deg: c[5] }), "_blank", "noopener");
    });
  }
}

// -- per-state intervals and best/worst states -------------------------------------------
const stateText = (s) => s.face + " / " + s.conveyor + " / θ = " + s.theta_deg + "°";
const ciText = (s) => pct(s.share) + " [" + pct(s.low) + ", " + pct(s.high) + "], n = " + s.n;
const CONVEYOR_DX = { left: -2, both: 0, right: 2 };
async function drawAnalysis() {
  const name = $("map-study").value, obj = $("map-object").value;
  if (!name || !obj || typeof Plotly === "undefined") return;
  let data;
  try {
    data = await api("/api/studies/" + encodeURIComponent(name) + "/analysis?object=" + encodeURIComponent(obj));
  } catch (e) { $("bestworst").querySelector("tbody").replaceChildren(el("tr", {}, el("td", { class: "error", text: e.message }))); return; }
  const traces = [];
  for (const face of ["front", "back"]) {
    for (const conveyor of ["left", "both", "right"]) {
      const pts = data.states.filter((p) => p.face === face && p.conveyor === conveyor);
      if (!pts.length) continue;
      traces.push({ type: "scatter", mode: "markers", name: face + " / " + conveyor,
        x: pts.map((p) => p.theta_deg + CONVEYOR_DX[conveyor]), y: pts.map((p) => p.share),
        error_y: { type: "data", symmetric: false, array: pts.map((p) => p.high - p.share),
          arrayminus: pts.map((p) => p.share - p.low), thickness: 1, width: 2 },
        marker: { size: 8, symbol: SYMBOL[conveyor] },
        customdata: pts.map((p) => [p.theta_deg, p.k, p.n, p.low, p.high]),
        hovertemplate: obj + " " + face + " / " + conveyor + ", θ = %{customdata[0]}°<br>" +
          "success %{customdata[1]} of %{customdata[2]} (%{y:.0%}), 95 % CI [%{customdata[3]:.0%}, %{customdata[4]:.0%}]<extra></extra>" });
    }
  }
  Plotly.react("ci-plot", traces, { height: 400, margin: { t: 40, b: 50, l: 60, r: 20 },
    title: { text: obj + ": success share per state (95 % Clopper–Pearson)", font: { size: 14 } },
    xaxis: { title: { text: "θ (deg)" }, range: [-185, 185], dtick: 45 },
    yaxis: { title: { text: "success share" }, range: [-0.03, 1.03], tickformat: ".0%" },
    legend: { orientation: "h", y: -0.2 } }, { displaylogo: false, responsive: true });

  const sel = data.selection;
  const bw = ["best", "worst"].map((which) => ({ type: "scatter", mode: "markers", name: which,
    x: sel.map((s) => s.object_id), y: sel.map((s) => s[which].share),
    error_y: { type: "data", symmetric: false, array: sel.map((s) => s[which].high - s[which].share),
      arrayminus: sel.map((s) => s[which].share - s[which].low), thickness: 1.5, width: 4 },
    marker: { size: 11, color: which === "best" ? "#1a7f37" : "#cf222e",
      symbol: which === "best" ? "triangle-up" : "triangle-down" },
    customdata: sel.map((s) => [stateText(s[which]), s[which].k, s[which].n, s[which].low, s[which].high, s[which].y_ma]),
    hovertemplate: "%{x} " + which + ": %{customdata[0]}<br>success %{customdata[1]} of %{customdata[2]} (%{y:.0%}), " +
      "95 % CI [%{customdata[3]:.0%}, %{customdata[4]:.0%}]<br>ȳ<sup>MA</sup> = %{customdata[5]:.2f}<extra></extra>" }));
  Plotly.react("bestworst-plot", bw, { height: 400, margin: { t: 40, b: 50, l: 60, r: 20 },
    title: { text: "best and worst state per core (" + name + ")", font: { size: 14 } },
    xaxis: { type: "category", title: { text: "core" } },
    yaxis: { title: { text: "success share" }, range: [-0.03, 1.03], tickformat: ".0%" },
    legend: { orientation: "h", y: -0.2 } }, { displaylogo: false, responsive: true });
  $("bestworst").querySelector("tbody").replaceChildren(...sel.map((s) => el("tr", { id: "bw-" + s.object_id },
    el("td", { text: s.object_id }), el("td", { class: "advice", text: s.advice }),
    el("td", { class: "best", text: stateText(s.best) }),
    el("td", { text: ciText(s.best) }), el("td", { class: "worst", text: stateText(s.worst) }),
    el("td", { text: ciText(s.worst) }),
    el("td", {}, ...["best", "worst"].map((w) => el("a", { class: "replay-link", href:
      replayUrl(name, s.object_id, s[w]), target: "_blank", rel: "noopener", text: w + " ",
      title: "replay run 0 of the " + w + " state in 3-D" }))))));
}

// -- calibration -----------------------------------------------------------------------------
async function drawCalibration() {
  const name = $("cal-select").value;
  if (!name || typeof Plotly === "undefined") return;
  let d;
  try { d = await api("/api/calibrations/" + encodeURIComponent(name)); } catch (e) {
    $("cal-summary").replaceChildren(el("p", { class: "error", text: e.message })); return;
  }
  const f = d.f05;
  const interval = f.low == null ? "no interval" : "95 % CI [" + f.low.toFixed(3) + ", " + f.high.toFixed(3) + "]";
  const rows = [["F0.5", f.value == null ? "–" : f.value.toFixed(3) + "  " + interval + (f.method ? " (" + f.method + ")" : "")]];
  if (f.cv_mean != null) rows.push(["F0.5, CV mean ± std over repeats", f.cv_mean.toFixed(3) + " ± " + (f.cv_std == null ? "–" : f.cv_std.toFixed(3))]);
  for (const k of ["precision", "recall", "accuracy"]) if (d.metrics[k] != null) rows.push([k, d.metrics[k].toFixed(3)]);
  for (const [k, v] of Object.entries(d.figures || {})) rows.push(["F0.5 " + k.replace(/_/g, " "), v.f05 == null ? "–" : v.f05.toFixed(3)]);
  rows.push(["real rows", String(d.n_real)], ["virtual runs", String(d.runs == null ? "–" : d.runs)],
    ["profile", String(d.profile)], ["written by", "calibrate " + d.kind]);
  $("cal-summary").replaceChildren(el("table", { id: "cal-figures" }, ...rows.map(([k, v]) =>
    el("tr", {}, el("th", { text: k }), el("td", { text: v })))), ...d.notes.map((n) => el("p", { class: "muted", text: n })));

  const c = d.confusion, total = c.tp + c.fp + c.fn + c.tn;
  const cell = [[c.tp, c.fp], [c.fn, c.tn]], names = [["TP", "FP"], ["FN", "TN"]];
  Plotly.react("cal-confusion", [{ type: "heatmap", x: ["real success", "real failure"], y: ["twin success", "twin failure"],
    z: cell, colorscale: [[0, "#f6f8fa"], [1, "#2f81f7"]], showscale: false,
    text: names.map((r, i) => r.map((n, j) => n + " = " + cell[i][j])), texttemplate: "%{text}", textfont: { size: 16 },
    customdata: cell.map((r) => r.map((v) => total ? v / total : 0)),
    hovertemplate: "%{y}, %{x}: %{z} (%{customdata:.1%} of " + total + ")<extra></extra>" }],
    { height: 380, margin: { t: 50, b: 40, l: 100, r: 20 }, yaxis: { autorange: "reversed" },
      title: { text: "confusion matrix: " + d.confusion_label, font: { size: 13 } } },
    { displaylogo: false, responsive: true });

  drawCalibrationRows(name, d);
  const sh = d.shares;
  const bars = [["real", "real", "#57606a"], ["sim", "twin", "#2f81f7"]].map(([key, label, color]) => ({
    type: "bar", name: label, x: sh.map((s) => s.object_id), y: sh.map((s) => s[key].share), marker: { color },
    error_y: { type: "data", symmetric: false, array: sh.map((s) => s[key].high - s[key].share),
      arrayminus: sh.map((s) => s[key].share - s[key].low), thickness: 1.5, width: 5, color: "#1d232a" },
    customdata: sh.map((s) => [s[key].k, s[key].n, s[key].low, s[key].high]),
    hovertemplate: "%{x} " + label + ": %{customdata[0]} of %{customdata[1]} (%{y:.0%}), " +
      "95 % CI [%{customdata[2]:.0%}, %{customdata[3]:.0%}]<extra></extra>" }));
  Plotly.react("cal-shares", bars, { height: 380, barmode: "group", margin: { t: 50, b: 50, l: 60, r: 20 },
    title: { text: "success share per core: real vs twin (95 % Clopper–Pearson)", font: { size: 13 } },
    xaxis: { type: "category", title: { text: "core" } },
    yaxis: { range: [0, 1.05], tickformat: ".0%", title: { text: "success share" } },
    legend: { orientation: "h", y: -0.2 } }, { displaylogo: false, responsive: true });
}
$("cal-select").addEventListener("change", drawCalibration);

// The real rows of a `calibrate run` folder, each run's prediction linked to its 3-D replay.
function drawCalibrationRows(name, d) {
  const box = $("cal-rows");
  if (!d.rows || !d.rows.length) {
    box.replaceChildren(el("p", { class: "muted", text: d.kind === "run" ? "no predictions.csv: no rows to replay" :
      "rows of 'calibrate evaluate' are not replayed (a 'calibrate run' folder lists its rows)" }));
    return;
  }
  const runs = d.rows[0].predicted.length;
  const head = el("tr", {}, ...["row", "core", "state", "real"].map((t) => el("th", { text: t })),
    ...Array.from({ length: runs }, (_, r) => el("th", { text: "twin, run " + r })));
  const body = d.rows.map((row) => el("tr", { id: "cal-row-" + row.row },
    el("td", { text: String(row.row) }), el("td", { text: row.object_id }),
    el("td", { text: row.face + " / " + row.conveyor + " / θ = " + row.theta_deg + "°" }),
    el("td", { text: row.success ? "success" : "failure" }),
    ...row.predicted.map((p, r) => el("td", {}, el("a", { class: "replay-link", target: "_blank",
      rel: "noopener", title: "replay this row as run " + r + " replayed it, in 3-D",
      href: "/replay?" + new URLSearchParams({ calibration: name, row: row.row, run: r }),
      text: (p ? "success" : "failure") + " ▶" })))));
  const more = d.rows_total > d.rows.length ? [el("p", { class: "muted", text:
    "the first " + d.rows.length + " of " + d.rows_total + " rows" })] : [];
  box.replaceChildren(el("h3", { text: "real rows: replay any in 3-D" }),
    el("table", { id: "cal-row-table" }, el("thead", {}, head), el("tbody", {}, ...body)), ...more);
}

// -- live transfer ---------------------------------------------------------------------------
const SVG = "http://www.w3.org/2000/svg";
const svgEl = (tag, attrs = {}, parent = null) => {
  const e = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.append(e);
  return e;
};
const mm = ([x, y]) => (1000 * x).toFixed(1) + "," + (-1000 * y).toFixed(1);  // F_T y up, SVG y down
let liveRun = null, liveGeometry = null;
function drawGeometry(g) {
  const svg = $("schematic");
  svg.replaceChildren();
  svgEl("polygon", { class: "gap", points: g.gap.map(mm).join(" ") }, svg);
  for (const b of g.belts) {
    svgEl("polygon", { class: "belt", id: "belt-" + b.unit + "-" + b.belt, points: b.polygon.map(mm).join(" ") }, svg);
    const cx = b.polygon.reduce((a, p) => a + p[0], 0) / 4, cy = b.polygon.reduce((a, p) => a + p[1], 0) / 4;
    const t = svgEl("text", { class: "belt-label", id: "belt-label-" + b.unit + "-" + b.belt,
      x: (1000 * cx).toFixed(0), y: (-1000 * cy + 6).toFixed(0), "text-anchor": "middle" }, svg);
    t.textContent = b.unit.toUpperCase() + " " + b.belt;
  }
  svgEl("line", { class: "axis", x1: -700, y1: 0, x2: 600, y2: 0 }, svg);
  for (const b of g.barriers) {
    const [p, q] = b.segment;
    svgEl("line", { class: "barrier", id: "barrier-" + b.unit + "-" + b.which, x1: 1000 * p[0], y1: -1000 * p[1],
      x2: 1000 * q[0], y2: -1000 * q[1] }, svg);
  }
  svgEl("polygon", { class: "object", id: "object" }, svg);
  svgEl("line", { class: "heading", id: "heading" }, svg);
  const cap = svgEl("text", { class: "caption", id: "schematic-caption", x: -690, y: -222 }, svg);
  cap.textContent = "";
}
function drawFrame(run, f) {
  const obj = $("object");
  if (!obj || !f) return;
  obj.setAttribute("points", f.polygon.map(mm).join(" "));
  obj.setAttribute("data-t", f.t_s);
  const [cx, cy] = f.centre, th = f.theta_deg * Math.PI / 180;
  const h = $("heading");
  h.setAttribute("x1", 1000 * cx); h.setAttribute("y1", -1000 * cy);
  h.setAttribute("x2", 1000 * cx + 60 * Math.cos(th)); h.setAttribute("y2", -1000 * cy - 60 * Math.sin(th));
  for (const unit of ["tm", "tu"]) {
    for (const which of ["near", "far"]) {
      const b = $("barrier-" + unit + "-" + which), on = f.barriers[unit][which];
      b.classList.toggle("interrupted", on);
      b.setAttribute("data-interrupted", on ? "1" : "0");
    }
    for (const belt of ["left", "right"]) {
      const v = f.belts[unit][belt], label = $("belt-label-" + unit + "-" + belt);
      const arrow = v === 0 ? "stopped" : v > 0 ? Math.abs(v).toFixed(2) + " m/s →" : "← " + Math.abs(v).toFixed(2) + " m/s";
      label.textContent = unit.toUpperCase() + " " + belt + ": " + arrow;
    }
  }
  $("schematic-caption").textContent = run.object + " " + run.face + " / " + run.conveyor + " / θ = " + run.theta_deg +
    "°   t = " + f.t_s.toFixed(2) + " s   " + f.phase + "   on " + f.possessed_by;
}
function showTransfer(snap) {
  const run = snap.run;
  if (!run) { $("transfer-info").textContent = "no transfer yet: start one above"; return; }
  if (snap.geometry && JSON.stringify(snap.geometry) !== liveGeometry) {
    liveGeometry = JSON.stringify(snap.geometry);
    drawGeometry(snap.geometry);
  }
  drawFrame(run, snap.frame);
  const o = run.outcome;
  let text = "transfer " + run.id + ": " + run.state;
  if (o) text += " — " + o.status + (o.success != null ? ", success = " + o.success + " (y1 = " + o.y1 + ", y2 = " + (o.y2 == null ? "–" : o.y2) + ")" : "") +
    (o.t_end_s != null ? ", t_end = " + o.t_end_s.toFixed(2) + " s" : "") + (o.message ? " (" + o.message + ")" : "");
  $("transfer-info").textContent = text;
  $("transfer-info").setAttribute("data-state", run.state);
  $("transfer-submit").disabled = run.state === "running";
  liveRun = run;
}
let transferEvents = 0;
function connectTransfer() {
  const source = new EventSource("/api/transfer/live");
  source.addEventListener("transfer", (ev) => {
    transferEvents += 1;
    $("schematic").setAttribute("data-events", transferEvents);
    showTransfer(JSON.parse(ev.data));
  });
}
$("tr-object").replaceChildren(...Array.from({ length: 37 }, (_, i) => el("option", { value: "o" + (i + 1), text: "o" + (i + 1) })));
$("transfer-form").addEventListener("submit", async (ev) => {
  ev.preventDefault();
  const msg = $("transfer-message");
  const form = new FormData(ev.target);
  const body = {};
  for (const k of ["object", "face", "conveyor", "theta_deg", "seed", "speed", "dock_error"]) body[k] = form.get(k);
  body.dock_error = String(body.dock_error).split(",").map((v) => v.trim());
  msg.className = ""; msg.textContent = "starting ...";
  try {
    const r = await api("/api/transfer", { method: "POST", headers: {
      "Content-Type": "application/json", Authorization: "Bearer " + token() }, body: JSON.stringify(body) });
    msg.className = "ok"; msg.textContent = "transfer " + r.id + " started";
  } catch (e) { msg.className = "error"; msg.textContent = e.message; }
});

// -- start -----------------------------------------------------------------------------------
(async () => {
  let config;
  try { config = await api("/api/config"); } catch (e) {
    $("live-status").textContent = e.message; return;
  }
  $("no-cps").hidden = config.cps;
  if (!config.cps) $("live-status").textContent = "";
  if (config.cps) {
    await loadAssets();
    setInterval(loadAssets, 2000);
    connectLive();
  }
  connectTransfer();
  $("no-calibrations").hidden = config.calibrations.length > 0;
  $("cal-select").replaceChildren(...config.calibrations.map((n) => el("option", { value: n, text: n })));
  if (config.studies.length || config.cps) {  // a floor's Experiment Manager may start one
    await loadStudies();
    setInterval(loadStudies, 2000);
    if (!config.cps) document.querySelector('nav .tab[data-tab="studies"]').click();
  } else {
    $("no-studies").hidden = false;
    if (!config.cps && config.calibrations.length) document.querySelector('nav .tab[data-tab="calibration"]').click();
    else if (!config.cps) document.querySelector('nav .tab[data-tab="live"]').click();
  }
})();
