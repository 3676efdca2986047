// canalid dashboard: renders the state and series the server sends over its WebSocket (a
// snapshot on connecting, then deltas a few times a second; format in docs/dashboard.md).
// Plain JavaScript and Debian's dygraphs; no framework, no build step.
"use strict";

const STATE_CLASS = { exciting: "phase-exciting", settling: "phase-settling",
  recovering: "phase-recovering", aborted: "phase-aborted", done: "phase-done" };
const FLAG_NAMES = [[1, "NaN"], [2, "windup"], [4, "low excitation"], [8, "ill-conditioned"],
  [16, "frozen"], [32, "out of bounds"]];

const points = new Map();   // series id -> [[t, value, sd], ...], oldest first
const charts = new Map();   // chart key -> {graph, ids, errorBars, dirty}
let state = { sites: [] };
let updates = 0;
let nowS = 0;
const closedHealth = new Set();  // sites whose health table the operator folded

function el(tag, attrs, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === "class") e.className = v; else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

function fmt(v, digits) {
  if (v === null || v === undefined || !Number.isFinite(v)) return "-";
  const a = Math.abs(v);
  if (digits !== undefined) return v.toFixed(digits);
  if (a !== 0 && (a >= 1e6 || a < 1e-3)) return v.toExponential(3);
  return v.toPrecision(5).replace(/\.?0+$/, "");
}

function flagText(flags) {
  const names = FLAG_NAMES.filter(([bit]) => flags & bit).map(([, n]) => n);
  return names.length ? names.join(", ") : "ok";
}

function addPoints(newPoints) {
  for (const [id, list] of Object.entries(newPoints)) {
    let series = points.get(id);
    if (!series) { series = []; points.set(id, series); }
    // A delta may repeat points the snapshot already had: keep time strictly increasing.
    const last = series.length ? series[series.length - 1][0] : -Infinity;
    for (const p of list) if (p[0] > last) series.push(p);
    const keep = 20000;
    if (series.length > keep) series.splice(0, series.length - keep);
    for (const c of charts.values()) if (c.ids.includes(id)) c.dirty = true;
  }
}

// Rows for dygraphs: the union of the series' times, null where a series has no point.
function rows(ids, errorBars) {
  const byTime = new Map();
  ids.forEach((id, k) => {
    for (const [t, v, sd] of points.get(String(id)) || []) {
      let row = byTime.get(t);
      if (!row) { row = new Array(ids.length).fill(null); byTime.set(t, row); }
      row[k] = errorBars ? [v, sd === null ? 0 : sd] : v;
    }
  });
  return [...byTime.keys()].sort((a, b) => a - b)
    .map((t) => [new Date(t * 1000), ...byTime.get(t)]);
}

function chart(parent, key, title, ids, labels, options) {
  ids = ids.filter((id) => id !== null && id !== undefined).map(String);
  if (!ids.length) return;
  let c = charts.get(key);
  // The page is rebuilt on every update; a chart's box moves into the new page, its graph kept.
  if (c && c.ids.join() === ids.join()) {
    parent.append(c.box);
    return;
  }
  const box = el("div", { "data-chart": key }, el("div", { class: "chart-title" }, title));
  const div = el("div", { class: "chart" });
  box.append(div);
  parent.append(box);
  const data = rows(ids, options.errorBars);
  if (!data.length) data.push([new Date(), ...ids.map(() => (options.errorBars ? [null, null] : null))]);
  const graph = new Dygraph(div, data, Object.assign({ labels: ["time", ...labels],
    connectSeparatedPoints: true, legend: "follow", labelsKMB: true, axisLabelFontSize: 11,
    digitsAfterDecimal: 3,
    animatedZooms: false }, options));
  c = { graph, ids, errorBars: !!options.errorBars, dirty: false, div, box };
  charts.set(key, c);
}

function redrawDirty() {
  for (const c of charts.values()) {
    if (!c.dirty || !c.div.isConnected) continue;
    c.dirty = false;
    const data = rows(c.ids, c.errorBars);
    if (data.length) c.graph.updateOptions({ file: data });
  }
}

function bandUnderlay(min, max) {
  return (ctx, area, g) => {
    const top = g.toDomYCoord(max), bottom = g.toDomYCoord(min);
    ctx.fillStyle = "rgba(27, 122, 58, 0.08)";
    ctx.fillRect(area.x, top, area.w, bottom - top);
    ctx.strokeStyle = "rgba(176, 0, 32, 0.7)";
    ctx.setLineDash([4, 3]);
    for (const y of [top, bottom]) {
      ctx.beginPath(); ctx.moveTo(area.x, y); ctx.lineTo(area.x + area.w, y); ctx.stroke();
    }
    ctx.setLineDash([]);
  };
}

function lineUnderlay(value) {
  return (ctx, area, g) => {
    if (value === null || !Number.isFinite(value)) return;
    const y = g.toDomYCoord(value);
    ctx.strokeStyle = "rgba(29, 53, 87, 0.8)";
    ctx.setLineDash([6, 4]);
    ctx.beginPath(); ctx.moveTo(area.x, y); ctx.lineTo(area.x + area.w, y); ctx.stroke();
    ctx.setLineDash([]);
  };
}

// Finds a channel's last value and series among a site's sources.
function channelOf(site, name) {
  for (const s of site.sources) for (const c of s.channels) if (c.name === name) return c;
  return null;
}

function fact(label, role, text, extra) {
  const value = el("span", Object.assign({ class: "value", "data-role": role }, extra || {}), text);
  return el("span", {}, label + ": ", value);
}

function renderExperiment(facts, experiment) {
  if (!experiment) { facts.append(fact("experiment", "phase", "none")); return; }
  const phase = fact("experiment " + (experiment.experiment || "-"), "phase", experiment.state);
  phase.lastChild.classList.add(STATE_CLASS[experiment.state] || "phase-idle");
  facts.append(phase);
  const progress = experiment.num_steps > 0
    ? `${experiment.step + 1} / ${experiment.num_steps} (${Math.round(100 * (experiment.step + 1) / experiment.num_steps)} %)`
    : "-";
  facts.append(fact("step", "progress", progress));
  facts.append(fact("setpoint " + (experiment.setpoint_channel || ""), "setpoint", fmt(experiment.setpoint, 3)));
  if (experiment.reason) facts.append(fact("reason", "reason", experiment.reason));
}

function renderModels(box, reach, prefix) {
  if (!reach.models.length) return;
  const table = el("table", { "data-role": "models" },
    el("tr", {}, el("th", {}, "model"), el("th", {}, "estimator"), el("th", {}, "parameters (± 2σ)"),
      el("th", {}, "samples"), el("th", {}, "prediction error"), el("th", {}, "health"),
      el("th", {}, "age")));
  for (const m of reach.models) {
    const cells = el("td", {});
    m.params.forEach((p, i) => {
      if (i) cells.append(" · ");
      const sigma = p.std !== null ? " ± " + fmt(2 * p.std) : "";
      cells.append(el("span", { "data-param": p.name, "data-value": String(p.value) },
        `${p.name} ${fmt(p.value)}${sigma}`));
    });
    table.append(el("tr", { "data-kind": m.kind, "data-estimator": m.estimator },
      el("td", {}, m.kind), el("td", {}, m.estimator), cells,
      el("td", { class: "num", "data-role": "samples" }, String(m.samples_used)),
      el("td", { class: "num" }, fmt(m.prediction_error_rms)),
      el("td", { class: m.flags ? "flagged" : "" }, flagText(m.flags)),
      el("td", { class: "num" }, fmt(m.age_s, 1) + " s")));
  }
  box.append(table);
  const grid = el("div", { class: "params" });
  box.append(grid);
  for (const m of reach.models) {
    if (m.estimator === "batch") continue;
    const batch = reach.models.find((b) => b.kind === m.kind && b.estimator === "batch");
    for (const p of m.params) {
      const batchParam = batch ? batch.params.find((b) => b.name === p.name) : null;
      chart(grid, `${prefix}|${reach.name}|${m.kind}|${m.estimator}|${p.name}`,
        `${m.kind} ${p.name} (${m.estimator}, ± 2σ${batchParam ? "; dashed: batch" : ""})`,
        [p.series], [p.name], { errorBars: true, sigma: 2,
          underlayCallback: lineUnderlay(batchParam ? batchParam.value : null) });
    }
  }
}

// Builds a reach's box inside `parent` (in the document, so dygraphs can size its charts).
function renderReach(parent, site, layout, reach) {
  const box = el("div", { class: "reach", "data-reach": reach.name });
  box.append(el("h3", {}, "reach " + reach.name));
  const facts = el("div", { class: "facts" });
  const charts_ = el("div", { class: "charts" });
  box.append(facts, charts_);
  parent.append(box);
  if (layout) {
    const level = channelOf(site, layout.level);
    facts.append(fact("level", "level", level ? fmt(level.value, 3) : "-"), " m");
    facts.append(fact("safety band", "band", `${fmt(layout.level_min_m, 3)} .. ${fmt(layout.level_max_m, 3)}`), " m");
    const inflow = channelOf(site, layout.inflow), outflow = channelOf(site, layout.outflow);
    facts.append(fact("inflow", "inflow", inflow ? fmt(inflow.value, 3) : "-"), " m³/s");
    facts.append(fact("outflow", "outflow", outflow ? fmt(outflow.value, 3) : "-"), " m³/s");
    const actuator = channelOf(site, layout.actuator);
    facts.append(fact("actuator " + layout.actuator, "actuator", actuator ? fmt(actuator.value, 3) : "-"));
    const position = layout.actuator_position ? channelOf(site, layout.actuator_position) : null;
    if (position) facts.append(fact("position", "position", fmt(position.value, 3)));
    renderExperiment(facts, reach.experiment);
    const key = `${site.prefix}|${reach.name}`;
    if (level) chart(charts_, key + "|level", `level ${layout.level} (m; band ${layout.level_min_m} .. ${layout.level_max_m})`,
      [level.series], ["level"], { underlayCallback: bandUnderlay(layout.level_min_m, layout.level_max_m) });
    chart(charts_, key + "|flows", "flows (m³/s)", [inflow && inflow.series, outflow && outflow.series],
      ["inflow", "outflow"].filter((_, k) => [inflow, outflow][k] && [inflow, outflow][k].series !== null), {});
    const act = [actuator, position].filter((c) => c && c.series !== null);
    chart(charts_, key + "|actuator", "actuator setpoint and position", act.map((c) => c.series),
      act.map((c) => c.name), { stepPlot: true });
  } else {
    renderExperiment(facts, reach.experiment);
  }
  renderModels(box, reach, site.prefix);
}

function renderSources(site) {
  const table = el("table", { "data-role": "sources" }, el("tr", {}, el("th", {}, "PLC"),
    el("th", {}, "status"), el("th", {}, "round trip"), el("th", {}, "samples"),
    el("th", {}, "dropped"), el("th", {}, "age")));
  for (const s of site.sources) {
    table.append(el("tr", { "data-source": s.name }, el("td", {}, s.name),
      el("td", { class: s.status ? "flagged" : "" }, s.status ? `error ${s.status}` : "ok"),
      el("td", { class: "num" }, fmt(s.round_trip_s * 1000, 1) + " ms"),
      el("td", { class: "num" }, String(s.samples)), el("td", { class: "num" }, String(s.dropped)),
      el("td", { class: "num" }, fmt(s.age_s, 1) + " s")));
  }
  return table;
}

function renderHealth(site) {
  const details = el("details", { "data-role": "health" }, el("summary", {}, "daemon health"));
  const table = el("table", {}, el("tr", {}, el("th", {}, "component"), el("th", {}, "counters"),
    el("th", {}, "gauges")));
  for (const h of site.health) {
    const list = (o) => Object.entries(o).map(([k, v]) => `${k} ${typeof v === "number" ? fmt(v) : v}`).join(" · ");
    table.append(el("tr", { "data-component": h.component }, el("td", {}, h.component),
      el("td", {}, list(h.counters)), el("td", {}, list(h.gauges))));
  }
  details.append(table);
  details.open = !closedHealth.has(site.prefix);
  details.addEventListener("toggle", () => {
    if (details.open) closedHealth.delete(site.prefix); else closedHealth.add(site.prefix);
  });
  return details;
}

function render() {
  const main = document.getElementById("sites");
  main.replaceChildren();
  if (!state.sites.length) {
    main.append(el("p", { class: "empty" }, "Waiting for canalidd's messages on the bus."));
  }
  for (const site of state.sites) {
    const section = el("section", { class: "site", "data-site": site.prefix });
    main.append(section);
    section.append(el("h2", {}, `site ${site.prefix}` + (site.layout && site.layout.version ? ` (canalid ${site.layout.version})` : "")));
    if (!site.layout) {
      section.append(el("p", { class: "empty" }, "No configuration seen yet (it is published when canalidd starts; or pass --config)."));
    }
    if (site.layout_problem) section.append(el("p", { class: "problem" }, site.layout_problem));
    if (site.malformed) section.append(el("p", { class: "problem" }, `${site.malformed} malformed messages ignored`));
    const names = new Set(site.reaches.map((r) => r.name));
    const layouts = site.layout ? site.layout.reaches : [];
    for (const l of layouts) names.add(l.name);
    for (const name of [...names].sort()) {
      const reach = site.reaches.find((r) => r.name === name) || { name, experiment: null, models: [] };
      renderReach(section, site, layouts.find((l) => l.name === name), reach);
    }
    section.append(renderSources(site), renderHealth(site));
  }
  document.getElementById("updates").textContent = String(updates);
  document.getElementById("now").textContent = nowS ? new Date(nowS * 1000).toISOString() : "-";
  redrawDirty();
}

function connect(delayMs) {
  const url = new URL("ws", location.href);
  url.protocol = location.protocol === "https:" ? "wss:" : "ws:";
  const socket = new WebSocket(url);
  const status = document.getElementById("connection");
  socket.onopen = () => { status.textContent = "live"; delayMs = 500; };
  socket.onmessage = (event) => {
    const message = JSON.parse(event.data);
    if (message.type === "snapshot") points.clear();
    addPoints(message.points);
    state = message.state;
    nowS = message.now;
    updates += 1;
    render();
  };
  socket.onclose = () => {
    status.textContent = "reconnecting";
    setTimeout(() => connect(Math.min(delayMs * 2, 5000)), delayMs);
  };
}

connect(500);
