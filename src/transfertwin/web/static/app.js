// transfertwin console: plain JS, no build step, nothing loaded from outside the console.
"use strict";

const params = new URLSearchParams(location.search);
if (params.has("token")) {
  sessionStorage.setItem("tt_token", params.get("token"));
  params.delete("token");
  history.replaceState(null, "", location.pathname + (params.toString() ? "?" + params : ""));
}
const token = () => sessionStorage.getItem("tt_token") || document.getElementById("order-token").value;
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
    if (b.dataset.tab === "studies") drawMap();
  });
}
if (sessionStorage.getItem("tt_token")) $("token-label").hidden = true;

// -- assets and live values --------------------------------------------------------------
let assetIds = [];
async function loadAssets() {
  let data;
  try { data = await api("/api/assets"); } catch (e) { return; }
  $("kg-error").hidden = !data.kg_error;
  $("kg-error").textContent = data.kg_error || "";
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

function fillOrderForm(data) {
  const fill = (sel, values, keep) => {
    const s = $(sel);
    const head = keep ? [...s.options].slice(0, 1) : [];
    s.replaceChildren(...head, ...values.map((v) => el("option", { value: v, text: v })));
  };
  fill("order-object", data.objects, false);
  fill("order-source", data.units, true);
  fill("order-target", data.units, false);
}

async function showAas(id) {
  $("aas").hidden = false;
  $("aas-id").textContent = id;
  const body = $("aas-body");
  body.replaceChildren(el("p", { class: "muted", text: "reading over OPC UA ..." }));
  try {
    const data = await api("/api/assets/" + encodeURIComponent(id) + "/aas");
    body.replaceChildren();
    for (const sm of data.submodels) {
      const table = el("table", {}, el("tr", {}, el("th", { text: "element" }), el("th", { text: "kind" }), el("th", { text: "value" })));
      for (const e of sm.elements) {
        table.append(el("tr", {}, el("td", { text: e.id_short }), el("td", { text: e.kind }),
          el("td", { text: "value" in e ? fmt(e.value) : "" })));
      }
      body.append(el("details", { class: "submodel", "data-submodel": sm.id_short },
        el("summary", { text: sm.id_short + " (" + sm.elements.length + ")" }), table));
    }
  } catch (e) {
    body.replaceChildren(el("p", { class: "error", text: e.message }));
  }
}

let events = 0;
function connectLive() {
  const source = new EventSource("/api/live");
  source.addEventListener("live", (ev) => {
    const data = JSON.parse(ev.data);
    events += 1;
    $("live-status").textContent = "live: " + events + " updates, " + new Date().toLocaleTimeString();
    for (const [id, online] of Object.entries(data.online)) {
      const tr = $("asset-" + id);
      if (!tr) continue;
      const cell = tr.querySelector(".c-reachable");
      cell.textContent = online ? "online" : "offline";
      cell.className = "c-reachable " + (online ? "on" : "off");
      const vals = data.values[id] || {};
      tr.querySelector(".c-live").replaceChildren(el("span", { class: "live",
        text: Object.entries(vals).map(([k, v]) => k + "=" + fmt(v)).join("  ") }));
    }
    renderOrders(data.orders);
  });
  source.onerror = () => { $("live-status").textContent = "live: reconnecting ..."; };
}

// -- orders --------------------------------------------------------------------------------
function renderOrders(orders) {
  const tbody = document.querySelector("#orders tbody");
  tbody.replaceChildren(...orders.slice().reverse().map((o) => {
    const steps = el("ol", { class: "steps" }, ...o.steps.map((s) => el("li", { text: s.text })));
    const tr = el("tr", { id: "order-" + o.id, "data-state": o.state });
    for (const v of [o.id, o.operation || "", o.object, o.source, o.target, o.state, o.outcome || ""]) {
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
  if (changed[sel.value] && !$("tab-studies").hidden) drawMap();
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
$("map-study").addEventListener("change", () => { fillObjects(); drawMap(); });
$("map-object").addEventListener("change", drawMap);

const SYMBOL = { left: "triangle-up", both: "circle", right: "triangle-down" };
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
      angularaxis: { rotation: 90, direction: "counterclockwise", dtick: 30 },
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
        customdata: pts.map((p) => [conveyor, p.n, p.successes, p.share, face]),
        marker: { size: 10, symbol: SYMBOL[conveyor], color: pts.map((p) => p.share),
          cmin: 0, cmax: 1, colorscale: [[0, "#cf222e"], [0.5, "#e3b341"], [1, "#1a7f37"]],
          showscale: !traces.some((t) => t.marker && t.marker.showscale), colorbar: { title: { text: "success" }, len: 0.6 },
          line: { width: 0.5, color: "#333" } },
        hovertemplate: obj + " %{customdata[4]}, θ = %{theta}, conveyor %{customdata[0]}<br>" +
          "success %{customdata[2]} of %{customdata[1]} (%{customdata[3]:.0%})<extra></extra>" });
    }
  });
  Plotly.react("polar", traces, layout, { displaylogo: false, responsive: true });
}

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
  if (config.studies.length) {
    await loadStudies();
    setInterval(loadStudies, 2000);
    if (!config.cps) document.querySelector('nav .tab[data-tab="studies"]').click();
  } else {
    $("no-studies").hidden = false;
  }
})();
