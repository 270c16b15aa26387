/* boustro serve: planning as the area and the options are edited: when to ask the server, the
   progress bar, and where each plan's time went (window.boustro.phases). Loaded before app.js,
   whose state, request(), drawPlan(), clearPlan() and showError() it calls once the page runs. */
"use strict";

// -- planning as the user edits ----------------------------------------------------------------
// A committed edit (a closed drawing, a dragged vertex dropped, a file, a choice, a field left
// or Enter) is planned at once; typing in a field waits TYPING_MS after the last key, so that
// "12" is not planned as "1" first. An edit that leaves the request as it was plans nothing.
const TYPING_MS = 60;
// The estimate before planning is asked only of a plan still running after ESTIMATE_AFTER_MS
// (a quick plan needs no bar), and the bar itself shows from then on.
const ESTIMATE_AFTER_MS = 150;
let timer = null;
function typing(e) {
  return !!e && e.type === "input" && e.target instanceof HTMLInputElement
    && e.target.type !== "checkbox";
}

function edited(e) {
  clearTimeout(timer);
  if (typing(e)) {
    state.lastEdit = performance.now();
    timer = setTimeout(replan, TYPING_MS);
    return;
  }
  if (state.outer.length >= 3 && JSON.stringify(request()) === state.sentBody) return;
  state.lastEdit = performance.now();
  replan();
}

async function postJSON(url, body) {
  const r = await fetch(url, { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  return r;
}

async function errorOf(r) {
  try { return (await r.json()).error || `HTTP ${r.status}`; } catch (_) { return `HTTP ${r.status}`; }
}

// The bar moves in steps of PROGRESS_TICK_MS, not as a 60 fps CSS animation: the server plans
// on this machine, and a page repainting every frame takes 10-15% of a core from it.
const PROGRESS_TICK_MS = 250;
function progress(on, seconds, text, since) {
  clearInterval(progress.ticker);
  $("progress").hidden = !on;
  if (!on) return;
  const bar = $("bar");
  const label = text || "planning…";
  const t0 = since === undefined ? performance.now() : since;
  const tick = () => {
    const s = (performance.now() - t0) / 1000;
    if (seconds > 0.5) {  // filled over the estimate
      bar.style.left = "0";
      bar.style.width = `${Math.min(95, (95 * s) / seconds)}%`;
    } else {  // a block sliding across, one pass in 2 s
      bar.style.width = "30%";
      bar.style.left = `${((s % 2) / 2) * 130 - 30}%`;
    }
    $("progress-text").textContent = s >= 1 ? `${label} (${s.toFixed(0)} s)` : label;
  };
  tick();
  progress.ticker = setInterval(tick, PROGRESS_TICK_MS);
}

function serverTiming(r) {
  // {parse, plan, answer, encode} in ms, from the answer's Server-Timing header
  const out = {};
  for (const m of (r.headers.get("Server-Timing") || "").matchAll(/(\w+);dur=([0-9.]+)/g)) {
    out[m[1]] = Number(m[2]);
  }
  return out;
}

function askEstimate(text, plan, since) {
  // a plan still running: the bar, filled over the estimate when that says more than 0.5 s
  if (!state.inFlight || state.planNo !== plan) return;
  progress(true, 0, "planning…", since);
  postJSON("/api/estimate", JSON.parse(text)).then(async (r) => {
    if (!r.ok || !state.inFlight || state.planNo !== plan) return;
    const f = (await r.json()).fields[0];
    if (f && f.seconds > 0.5 && state.inFlight && state.planNo === plan) {
      progress(true, f.seconds, f.text, since);
    }
  }).catch(() => {});
}

async function replan() {
  if (state.outer.length < 3) return;
  const text = JSON.stringify(request());
  if (state.inFlight) { state.pending = text !== state.sentBody; return; }
  state.inFlight = true;
  state.pending = false;
  state.sentBody = text;
  const plan = state.planNo = (state.planNo || 0) + 1;
  const t = { edit: state.lastEdit, sent: performance.now() };
  state.estimateTimer = setTimeout(() => askEstimate(text, plan, t.sent), ESTIMATE_AFTER_MS);
  try {
    const r = await fetch("/api/plan", { method: "POST",
      headers: { "Content-Type": "application/json" }, body: text });
    t.answered = performance.now();
    if (!r.ok) { showError(await errorOf(r)); clearPlan(); }
    else if (!state.pending) {
      t.server = serverTiming(r);
      const answer = await r.json();
      t.parsed = performance.now();
      drawPlan(answer, t);
    }
  } catch (e) {
    showError("the server did not answer: " + e);
  } finally {
    state.inFlight = false;
    clearTimeout(state.estimateTimer);
    progress(false);
    if (state.pending) replan();
  }
}
