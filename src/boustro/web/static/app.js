/* boustro serve: the page. Draw or drop an area, plan it through the JSON API as it is edited,
   show the plan and its summary, download the mission. No network beyond this server. */
"use strict";

const $ = (id) => document.getElementById(id);
const state = {
  config: null,
  outer: [],            // [[lat, lng], ...] the area's outer ring
  holes: [],            // [[[lat, lng], ...], ...]
  draft: null,          // {kind: "outer" | "hole", points: [...]} while drawing
  name: "",             // the area's name (from a file)
  start: null,          // [lat, lng] or null
  pickingStart: false,
  fields: [],           // features of the last opened file
  lastEdit: 0,          // performance.now() of the last edit
  inFlight: false,
  pending: false,
  planSeq: 0,           // plans drawn
  errorSeq: 0,          // errors shown
  timings: [],          // ms from the last edit to the drawn plan, per plan
  serverTimings: [],    // ms of planning in the server (its Server-Timing "plan"), per plan
  phases: [],           // per plan: where its ms went (see replan), from edit to frame
  sentBody: null,       // the request last sent to /api/plan (an edit that changes nothing
                        // is not planned again)
  lastPlan: null,
};
window.boustro = state;

// -- the map: a plain background, a graticule, a scale bar; tiles only if configured ----------
const map = L.map("map", { doubleClickZoom: false, zoomSnap: 0.25 }).setView([52.0, 5.66], 15);
L.control.scale({ imperial: false, maxWidth: 150 }).addTo(map);
const graticule = L.layerGroup().addTo(map);
const areaLayer = L.layerGroup().addTo(map);
const planLayer = L.layerGroup().addTo(map);
const draftLayer = L.layerGroup().addTo(map);

function niceStep(span) {
  const raw = span / 6;
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  for (const m of [1, 2, 5, 10]) if (m * p >= raw) return m * p;
  return 10 * p;
}

function fmtDeg(v, step) {
  const digits = Math.max(0, Math.min(8, -Math.floor(Math.log10(step))));
  return v.toFixed(digits) + "°";
}

function drawGraticule() {
  graticule.clearLayers();
  const b = map.getBounds();
  const south = Math.max(-85, b.getSouth()), north = Math.min(85, b.getNorth());
  const west = b.getWest(), east = b.getEast();
  const step = niceStep(Math.max(north - south, (east - west) / 2));
  const style = { color: "#99a", weight: 0.6, opacity: 0.7, interactive: false };
  for (let lat = Math.ceil(south / step) * step; lat <= north; lat += step) {
    graticule.addLayer(L.polyline([[lat, west], [lat, east]], style));
    graticule.addLayer(L.marker([lat, west], { interactive: false, icon: L.divIcon({
      className: "grat-label", html: fmtDeg(lat, step), iconSize: null, iconAnchor: [-2, 12] }) }));
  }
  for (let lng = Math.ceil(west / step) * step; lng <= east; lng += step) {
    graticule.addLayer(L.polyline([[south, lng], [north, lng]], style));
    graticule.addLayer(L.marker([south, lng], { interactive: false, icon: L.divIcon({
      className: "grat-label", html: fmtDeg(lng, step), iconSize: null, iconAnchor: [-2, 14] }) }));
  }
}
map.on("moveend zoomend resize", drawGraticule);
drawGraticule();

// -- the area: drawing, holes, dragging vertices ---------------------------------------------
function vertexIcon(hole) {
  return L.divIcon({ className: "vertex" + (hole ? " hole" : ""), iconSize: [12, 12] });
}

function drawArea() {
  areaLayer.clearLayers();
  if (state.outer.length >= 3) {
    L.polygon([state.outer, ...state.holes], {
      color: "#1565c0", weight: 2, fillOpacity: 0.08, interactive: false,
    }).addTo(areaLayer);
  }
  const rings = [state.outer, ...state.holes];
  rings.forEach((ring, r) => ring.forEach((pt, i) => {
    const m = L.marker(pt, { draggable: true, icon: vertexIcon(r > 0), keyboard: false });
    m.on("drag", (e) => { const ll = e.target.getLatLng(); ring[i] = [ll.lat, ll.lng]; redrawShape(); });
    m.on("dragend", () => { drawArea(); edited(); });
    m.on("click", (e) => { if (state.draft) onMapClick(e); });
    m.addTo(areaLayer);
  }));
  if (state.start) {
    L.circleMarker(state.start, { radius: 6, color: "#2e7d32", fillOpacity: 0.9 })
      .bindTooltip("start (asked)").addTo(areaLayer);
  }
}

function redrawShape() {
  areaLayer.eachLayer((l) => { if (l instanceof L.Polygon) l.setLatLngs([state.outer, ...state.holes]); });
}

function drawDraft(cursor) {
  draftLayer.clearLayers();
  if (!state.draft) return;
  const pts = state.draft.points.slice();
  if (cursor) pts.push(cursor);
  const color = state.draft.kind === "hole" ? "#c62828" : "#1565c0";
  if (pts.length > 1) L.polyline(pts, { color, dashArray: "4 4", interactive: false }).addTo(draftLayer);
  state.draft.points.forEach((p) => L.circleMarker(p, { radius: 4, color, interactive: false }).addTo(draftLayer));
}

function startDrawing(kind) {
  if (kind === "hole" && state.outer.length < 3) { showError("draw the area first, then its holes"); return; }
  state.draft = { kind, points: [] };
  $("map").classList.add("drawing");
  $(kind === "hole" ? "hole" : "draw").classList.add("active");
  $("hint").textContent = "Click the vertices; click the first one (or double-click) to close; Esc cancels.";
}

function stopDrawing() {
  state.draft = null;
  draftLayer.clearLayers();
  $("map").classList.remove("drawing");
  $("draw").classList.remove("active");
  $("hole").classList.remove("active");
}

function closeDraft() {
  const d = state.draft;
  if (!d || d.points.length < 3) return;
  if (d.kind === "outer") {
    state.outer = d.points; state.holes = []; state.name = ""; $("field-row").hidden = true;
  }
  else state.holes.push(d.points);
  stopDrawing();
  $("hint").textContent = "Drag a vertex to move it; the plan follows.";
  drawArea();
  edited();
}

function onMapClick(e) {
  if (state.pickingStart) {
    state.pickingStart = false;
    $("start").classList.remove("active");
    state.start = [e.latlng.lat, e.latlng.lng];
    drawArea();
    edited();
    return;
  }
  const d = state.draft;
  if (!d) return;
  if (d.points.length >= 3) {
    const first = map.latLngToContainerPoint(d.points[0]);
    if (first.distanceTo(map.latLngToContainerPoint(e.latlng)) < 10) { closeDraft(); return; }
  }
  const last = d.points[d.points.length - 1];
  const here = map.latLngToContainerPoint(e.latlng);
  if (last && map.latLngToContainerPoint(last).distanceTo(here) < 3) return;  // a double-click
  d.points.push([e.latlng.lat, e.latlng.lng]);
  drawDraft();
}

map.on("click", onMapClick);
map.on("dblclick", () => closeDraft());
map.on("mousemove", (e) => { if (state.draft) drawDraft([e.latlng.lat, e.latlng.lng]); });
document.addEventListener("keydown", (e) => {
  if (e.key === "Escape") stopDrawing();
  if (e.key === "Enter" && state.draft) closeDraft();
});

// -- options -----------------------------------------------------------------------------------
function num(id) {
  const v = $(id).value.trim();
  return v === "" ? null : Number(v);
}

function options() {
  const o = {};
  const mode = $("mode").value;
  if (mode === "spacing") o.spacing = num("spacing");
  if (mode === "camera") {
    o.camera = [num("sensor_mm"), num("focal_mm"), num("image_px")];
    if (num("gsd") !== null) o.gsd = num("gsd");
  }
  if (mode === "swath") { o.swath = num("swath"); o.nadir_gap = num("nadir_gap"); }
  if (mode !== "spacing" && num("overlap") !== null) o.overlap = num("overlap");
  if ($("objective").value) o.objective = $("objective").value; // else the library's default
  if ($("method").value) o.method = $("method").value;
  if ($("direction").value) o[$("direction").value] = num("direction-value");
  const alt = num("altitude");
  if (alt !== null && !(mode === "camera" && o.gsd !== undefined)) o.altitude = alt;
  for (const k of ["speed", "turn_time", "turnaround"]) if (num(k) !== null) o[k] = num(k);
  if (num("turn_radius") !== null) {
    o.turn_radius = num("turn_radius");
    if ($("reverse").checked) o.reverse = true;
  }
  if (num("headland")) o.headland = num("headland");
  if ($("keep_inside").checked) o.keep_inside = true;
  o.layout = $("layout").value;
  if ($("decompose").value) o.decompose = $("decompose").value === "true";
  if (state.start) o.start = [state.start[1], state.start[0]];
  if ($("repair").checked) o.repair = true;
  return o;
}

function areaGeoJSON() {
  const ring = (pts) => { const r = pts.map(([lat, lng]) => [lng, lat]); r.push(r[0]); return r; };
  const geometry = { type: "Polygon", coordinates: [ring(state.outer), ...state.holes.map(ring)] };
  return { type: "Feature", properties: state.name ? { name: state.name } : {}, geometry };
}

function request(extra) {
  return Object.assign({ area: areaGeoJSON(), options: options() }, extra || {});
}

// -- planning as the user edits: planning.js ------------------------------------------------

function showError(text) {
  const box = $("error");
  box.textContent = text;
  box.hidden = false;
  state.errorSeq += 1;
}

function clearPlan() {
  planLayer.clearLayers();
  $("summary").innerHTML = "";
  $("downloads").innerHTML = "";
  state.lastPlan = null;
}

function arrowMarkers(coords) {
  // one arrow on every other segment of the path, turned along it (Mercator keeps angles)
  const out = [];
  for (let i = 0; i + 1 < coords.length; i += 2) {
    const a = map.project([coords[i][1], coords[i][0]], 20);
    const b = map.project([coords[i + 1][1], coords[i + 1][0]], 20);
    if (a.distanceTo(b) < 1) continue;
    const deg = Math.atan2(b.y - a.y, b.x - a.x) * 180 / Math.PI;
    const mid = [(coords[i][1] + coords[i + 1][1]) / 2, (coords[i][0] + coords[i + 1][0]) / 2];
    out.push(L.marker(mid, { interactive: false, icon: L.divIcon({
      className: "arrow", iconSize: [14, 14],
      html: `<div style="transform: rotate(${deg}deg)">➤</div>` }) }));
  }
  return out;
}

function drawPlan(answer, t) {
  const plan = Array.isArray(answer) ? answer[0] : answer;
  planLayer.clearLayers();
  $("error").hidden = true;
  const lines = [];
  for (const f of plan.geojson.features) {
    const role = f.properties.role;
    const ll = (c) => c.map(([x, y]) => [y, x]);
    if (role === "cell") {
      planLayer.addLayer(L.polygon(f.geometry.coordinates.map(ll), {
        color: "#7b1fa2", weight: 1, dashArray: "5 4", fill: false, interactive: false }));
    } else if (role === "transect") {
      const hole = f.properties.pass === "hole";
      lines.push(L.polyline(ll(f.geometry.coordinates), {
        color: hole ? "#ef6c00" : "#2e7d32", weight: 3, opacity: 0.85, className: "lane" }));
    } else if (role === "path") {
      planLayer.addLayer(L.polyline(ll(f.geometry.coordinates), {
        color: "#d35400", weight: 1.5, opacity: 0.9, interactive: false, className: "path" }));
      arrowMarkers(f.geometry.coordinates).forEach((m) => planLayer.addLayer(m));
      const s = f.geometry.coordinates[0];
      planLayer.addLayer(L.circleMarker([s[1], s[0]], { radius: 7, color: "#1b5e20",
        fillColor: "#66bb6a", fillOpacity: 1 }).bindTooltip("start"));
    }
  }
  lines.forEach((l) => planLayer.addLayer(l));
  summary(plan, Array.isArray(answer) ? answer.length : 1);
  downloads();
  state.lastPlan = plan;
  const drawn = performance.now();
  requestAnimationFrame(() => {
    const now = performance.now();
    const server = Object.values(t.server).reduce((a, b) => a + b, 0);
    state.timings.push(now - t.edit);
    state.serverTimings.push(t.server.plan === undefined ? null : t.server.plan);
    state.phases.push({  // ms: the edit's wait, HTTP beside the server's work, the server's
      // steps, reading the answer, drawing it, and the frame that shows it
      wait: t.sent - t.edit, http: t.answered - t.sent - server, server: t.server,
      read: t.parsed - t.answered, draw: drawn - t.parsed, frame: now - drawn, total: now - t.edit,
    });
    state.planSeq += 1;
  });
}

function fmt(v, digits) { return v === null || v === undefined ? "—" : Number(v).toFixed(digits); }

function summary(p, fields) {
  const rows = [
    ["field", p.name || "(drawn)"],
    ["lanes", `${p.n_transects} (${p.layout})`],
    ["turns", p.n_turns],
    ["path length", `${fmt(p.path_length_m, 1)} m (lanes ${fmt(p.transect_length_m, 1)} m)`],
    ["outside the area", p.outside_length_m !== undefined ? `${fmt(p.outside_length_m, 1)} m of the path` : "—"],
    ["time", p.duration_s !== undefined ? `${fmt(p.duration_s / 60, 1)} min at ${p.speed_m_s} m/s` : "give a speed"],
    ["coverage", p.covered_share !== undefined ? `${fmt(100 * p.covered_share, 3)}% (overlap ${fmt(100 * p.overlap_share, 1)}%)` : "—"],
    ["certificate", p.certified ? `certified optimum (${p.objective}), gap ${Number(p.gap).toExponential(1)}` : (p.gap != null ? `gap ${Number(p.gap).toPrecision(3)} (${p.objective}), not within tolerance` : `not certified (${p.method})`)],
    ["optimiser", `${p.method}, fitness ${p.fitness === null ? "undefined" : fmt(p.fitness, 6)}`],
    ["direction", `${fmt(p.angle_deg, 2)}° from east, bearing ${fmt(p.bearing_deg, 2)}°`],
    ["spacing", `${fmt(p.spacing_m, 2)} m${p.sensor ? " (" + p.sensor + ")" : ""}`],
    ["area", `${fmt(p.area_m2 / 1e4, 4)} ha, ${p.plan_crs}`],
  ];
  if (p.n_cells > 1) rows.push(["cells", p.n_cells]);
  if (fields > 1) rows.push(["fields", `${fields} (the first is shown)`]);
  for (const n of p.notes || []) rows.push(["note", n]);
  const t = $("summary");
  t.innerHTML = "";
  for (const [k, v] of rows) {
    const tr = t.insertRow();
    tr.insertCell().textContent = k;
    tr.insertCell().textContent = String(v);
  }
}

function downloads() {
  const box = $("downloads");
  box.innerHTML = "";
  for (const [name, exts] of Object.entries(state.config.formats)) {
    const b = document.createElement("button");
    b.type = "button";
    b.textContent = (exts[0] || name);
    b.dataset.format = name;
    b.title = `download the mission as ${name}`;
    b.addEventListener("click", () => download(name));
    box.appendChild(b);
  }
}

async function download(format) {
  const r = await postJSON("/api/export", request({ format }));
  if (!r.ok) { showError(await errorOf(r)); return; }
  const cd = r.headers.get("Content-Disposition") || "";
  const name = (cd.match(/filename="([^"]+)"/) || [null, "mission"])[1];
  const url = URL.createObjectURL(await r.blob());
  const a = document.createElement("a");
  a.href = url; a.download = name;
  document.body.appendChild(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

// -- files: open or drop ---------------------------------------------------------------------
function useFeature(f) {
  const rings = f.geometry.coordinates.map((r) => r.slice(0, -1).map(([x, y]) => [y, x]));
  state.outer = rings[0];
  state.holes = rings.slice(1);
  state.name = f.properties.name || "";
  stopDrawing();
  drawArea();
  map.fitBounds(L.latLngBounds(state.outer), { padding: [30, 30] });
  edited();
}

function useFields(fc) {
  state.fields = fc.features;
  const sel = $("field");
  sel.innerHTML = "";
  fc.features.forEach((f, i) => sel.add(new Option(f.properties.name || `field ${i + 1}`, i)));
  $("field-row").hidden = fc.features.length < 2;
  useFeature(fc.features[0]);
}

async function openFile(file) {
  const crs = $("file-crs").value.trim();
  const q = new URLSearchParams({ name: file.name });
  if (crs) q.set("crs", crs);
  const r = await fetch("/api/read?" + q, { method: "POST",
    headers: { "Content-Type": "application/octet-stream" }, body: await file.arrayBuffer() });
  if (!r.ok) { showError(await errorOf(r)); return; }
  $("error").hidden = true;
  $("hint").textContent = `${file.name}: drag a vertex to move it; the plan follows.`;
  useFields(await r.json());
}

$("file").addEventListener("change", (e) => { if (e.target.files[0]) openFile(e.target.files[0]); });
$("field").addEventListener("change", (e) => useFeature(state.fields[Number(e.target.value)]));
const mapEl = $("map");
mapEl.addEventListener("dragover", (e) => { e.preventDefault(); e.dataTransfer.dropEffect = "copy"; });
mapEl.addEventListener("drop", (e) => {
  e.preventDefault();
  if (e.dataTransfer.files.length) openFile(e.dataTransfer.files[0]);
});

// -- buttons and form --------------------------------------------------------------------------
$("draw").addEventListener("click", () => startDrawing("outer"));
$("hole").addEventListener("click", () => startDrawing("hole"));
$("clear").addEventListener("click", () => {
  state.sentBody = null;
  state.outer = []; state.holes = []; state.name = ""; $("field-row").hidden = true; stopDrawing(); drawArea(); clearPlan(); $("error").hidden = true;
});
$("example").addEventListener("click", async () => {
  const r = await fetch("/api/embedded");
  useFields(await r.json());
});
$("start").addEventListener("click", () => { state.pickingStart = true; $("start").classList.add("active"); });
$("start-clear").addEventListener("click", () => { state.start = null; drawArea(); edited(); });
$("mode").addEventListener("change", () => {
  const mode = $("mode").value;
  document.querySelectorAll("[data-mode]").forEach((el) => { el.hidden = !el.dataset.mode.split(" ").includes(mode); });
});
$("direction").addEventListener("change", () => { $("direction-row").hidden = !$("direction").value; });
document.querySelectorAll("#options input, #options select").forEach((el) => {
  el.addEventListener("input", edited);
  el.addEventListener("change", edited);
});

(async function init() {
  const r = await fetch("/api/config");
  state.config = await r.json();
  $("version").textContent = state.config.version;
  $("objective").add(new Option("default (time with a speed, else smith)", "", true, true));
  for (const name of state.config.objectives) $("objective").add(new Option(name, name));
  if (state.config.tiles) {
    L.tileLayer(state.config.tiles, { maxZoom: 20, attribution: "tiles: " + new URL(state.config.tiles.replace(/[{}]/g, "")).host }).addTo(map);
  }
  state.ready = true;
})();
