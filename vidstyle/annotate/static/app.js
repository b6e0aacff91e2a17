// vidstyle annotate: one page, no build step. Frames are fetched by decoded index from the server; the
// page never turns a playback time into a frame number. Segments are stored half-open [start, end). The
// performer choice is a decoded frame and a pixel of the input video (upright, pixel centres at integers).
"use strict";

const TOKEN = document.querySelector('meta[name="vidstyle-token"]').content;
// a server reachable beyond loopback needs the key it printed at start: from the URL fragment (#key=...,
// never sent to the server by the browser) or asked for on the first 401
let KEY = (location.hash.match(/[#&]key=([^&]*)/) || [])[1];
KEY = KEY ? decodeURIComponent(KEY) : "";
const withKey = (url) => (KEY ? `${url}${url.includes("?") ? "&" : "?"}key=${encodeURIComponent(KEY)}` : url);
const $ = (id) => document.getElementById(id);
const PERFORMER = "#ff3df2"; // the performer choice's colour (ring on the frame, diamond on the timeline)
const S = {
  videos: [], vid: null, frame: 0, frames: {}, timestamps: {}, overlays: {},
  revision: 0, classes: [], marks: {}, action: 0, pending: null,
  undo: [], redo: [], changes: 0, savedChanges: 0, saving: false, conflict: false, base: null,
  playing: false, saveTimer: null, picking: false,
};
window.vidstyle = S; // for tests and the curious

// ------------------------------------------------------------------ server
async function api(method, url, body, raw, asked) {
  const opts = { method, headers: {} };
  if (method !== "GET") opts.headers["X-Vidstyle-Token"] = TOKEN;
  if (KEY) opts.headers["X-Vidstyle-Secret"] = KEY;
  if (body !== undefined) {
    opts.body = raw ? body : JSON.stringify(body);
    opts.headers["Content-Type"] = raw ? "application/octet-stream" : "application/json";
  }
  const r = await fetch(url, opts);
  if (r.status === 401 && !asked) {
    const k = window.prompt("This annotation server needs the key it printed when it started (the part after #key=):");
    if (k) { KEY = k.trim().replace(/^.*#key=/, ""); return api(method, url, body, raw, true); }
  }
  let data = null;
  try { data = await r.json(); } catch (e) { data = null; }
  return { status: r.status, ok: r.ok, data };
}

// the marks in one canonical form (sorted, fixed key order) so the page's and the server's compare equal
function canon(m) {
  const t = [...m.transitions].sort((a, b) => a.frame - b.frame).map((x) => ({
    frame: x.frame, from_action: x.from_action, to_action: x.to_action, status: x.status,
    candidates: (x.candidates || []).map((c) => ({ clip: c.clip, time: c.time, status: c.status })) }));
  const s = [...m.segments].sort((a, b) => a.start - b.start).map((x) => ({ start: x.start, end: x.end, action: x.action }));
  const p = m.performer ? { frame: m.performer.frame, x: m.performer.x, y: m.performer.y } : null;
  return JSON.stringify({ transitions: t, segments: s, performer: p });
}
function baseOf(classes, marks) {
  const b = { classes: JSON.stringify(classes), marks: {} };
  for (const [id, m] of Object.entries(marks)) b.marks[id] = canon(m);
  return b;
}
function marksOf(state) {
  const out = {};
  for (const v of state.videos) out[v.id] = { transitions: v.transitions, segments: v.segments, performer: v.performer || null };
  return out;
}

async function load() {
  S.videos = (await api("GET", "/api/videos")).data;
  const sel = $("video");
  sel.innerHTML = "";
  for (const v of S.videos) {
    const o = document.createElement("option");
    o.value = v.id; o.textContent = `${v.id}: ${v.name}`;
    sel.appendChild(o);
  }
  await loadAnnotations();
  await selectVideo(S.videos[0].id);
}

async function loadAnnotations() {
  const a = (await api("GET", "/api/annotations")).data;
  S.revision = a.revision;
  S.classes = a.classes;
  S.marks = marksOf(a);
  S.base = baseOf(S.classes, S.marks);
  S.undo = []; S.redo = []; S.changes = S.savedChanges = 0; S.conflict = false;
  renderClasses();
  setStatus();
}

async function selectVideo(id) {
  if (S.vid) S.frames[S.vid.id] = S.frame;
  S.vid = S.videos.find((v) => v.id === id);
  $("video").value = id;
  if (!S.timestamps[id]) {
    S.timestamps[id] = (await api("GET", `/api/videos/${id}/timestamps`)).data;
    S.overlays[id] = (await api("GET", `/api/videos/${id}/overlays`)).data || {};
  }
  S.pending = null;
  S.picking = false;
  go(S.frames[id] || 0);
}

// ------------------------------------------------------------------ frames
function frameUrl(i) { return withKey(`/api/videos/${S.vid.id}/frames/${i}?v=${S.vid.sha256.slice(0, 12)}`); }

function go(i) {
  if (!S.vid) return;
  i = Math.max(0, Math.min(S.vid.frames - 1, Math.trunc(i)));
  S.frame = i;
  const img = $("frame");
  img.dataset.want = String(i);
  img.src = frameUrl(i);
  render();
}

$("frame").addEventListener("load", () => {
  const img = $("frame");
  const m = img.src.match(/\/videos\/([^/]+)\/frames\/(\d+)/);
  img.dataset.video = m[1];
  img.dataset.frame = m[2];
  fitFrame();
  drawOverlay();
  renderInfo();
  if (S.playing) schedulePlay();
});

function schedulePlay() {
  const ts = S.timestamps[S.vid.id];
  const i = S.frame;
  if (i >= S.vid.frames - 1) { S.playing = false; renderInfo(); return; }
  const dt = Math.max(0, (ts[i + 1] - ts[i]) * 1000 - (performance.now() - S.playShown));
  clearTimeout(S.playTimer);
  S.playTimer = setTimeout(() => { if (S.playing) { S.playShown = performance.now(); go(i + 1); } }, dt);
}

function togglePlay() {
  S.playing = !S.playing;
  if (S.playing) { S.playShown = performance.now(); schedulePlay(); } else clearTimeout(S.playTimer);
  renderInfo();
}

// ------------------------------------------------------------------ marks (every change is undoable)
function marks() { return S.marks[S.vid.id]; }
function snapshot() { return JSON.stringify({ classes: S.classes, marks: S.marks }); }
function change(fn) {
  const before = snapshot();
  fn();
  if (snapshot() === before) return;
  S.undo.push(before);
  if (S.undo.length > 1000) S.undo.shift();
  S.redo = [];
  changed();
}
function changed() {
  S.changes++;
  render();
  setStatus();
  clearTimeout(S.saveTimer);
  S.saveTimer = setTimeout(save, 800);
}
function restore(snap) { const s = JSON.parse(snap); S.classes = s.classes; S.marks = s.marks; renderClasses(); }
function undo() { if (!S.undo.length) return; S.redo.push(snapshot()); restore(S.undo.pop()); changed(); }
function redo() { if (!S.redo.length) return; S.undo.push(snapshot()); restore(S.redo.pop()); changed(); }

function segmentAt(f) { return marks().segments.find((s) => s.start <= f && f < s.end); }
function transitionAt(f) { return marks().transitions.find((t) => t.frame === f); }
function actionName() { return S.classes[S.action]; }

function markTransition() {
  const f = S.frame;
  change(() => {
    const t = transitionAt(f);
    if (t) { t.status = t.status === "accepted" ? "discarded" : "accepted"; return; }
    const segs = marks().segments;
    const before = segmentAt(f - 1) || segs.filter((s) => s.end <= f).sort((a, b) => b.end - a.end)[0];
    const after = segmentAt(f + 1) || segs.filter((s) => s.start > f).sort((a, b) => a.start - b.start)[0];
    const from = before ? before.action : actionName();
    let to = after ? after.action : actionName();
    marks().transitions.push({ frame: f, from_action: from, to_action: to, status: "accepted" });
    marks().transitions.sort((a, b) => a.frame - b.frame);
  });
}

function startSegment() { S.pending = S.frame; render(); }

function endSegment() {
  if (S.pending === null) { flash("press [ at the first frame of the segment first"); return; }
  const a = Math.min(S.pending, S.frame), b = Math.max(S.pending, S.frame) + 1;
  S.pending = null;
  change(() => {
    const out = [];
    for (const s of marks().segments) {            // the new segment replaces what it covers
      if (s.end <= a || s.start >= b) { out.push(s); continue; }
      if (s.start < a) out.push({ start: s.start, end: a, action: s.action });
      if (s.end > b) out.push({ start: b, end: s.end, action: s.action });
    }
    out.push({ start: a, end: b, action: actionName() });
    out.sort((x, y) => x.start - y.start);
    marks().segments = out;
  });
}

function pickAction(k) {         // the action of the next segment
  if (k >= S.classes.length) return;
  S.action = k;
  renderClasses();
  render();
}

function relabelHere(k) {        // Shift+digit: the action of the segment under the cursor
  if (k >= S.classes.length) return;
  S.action = k;
  renderClasses();
  if (segmentAt(S.frame)) change(() => { segmentAt(S.frame).action = S.classes[k]; });
  else flash("no segment at this frame to relabel");
}

function removeHere() {
  const f = S.frame;
  change(() => {
    const m = marks();
    if (transitionAt(f)) m.transitions = m.transitions.filter((t) => t.frame !== f);
    else m.segments = m.segments.filter((s) => !(s.start <= f && f < s.end));
  });
}

function decideCandidate(c, status) {
  const f = S.frame;
  change(() => {
    const t = transitionAt(f);
    if (!t) return;
    t.candidates = (t.candidates || []).filter((x) => !(x.clip === c.clip && x.time === c.time));
    t.candidates.push({ clip: c.clip, time: c.time, status });
  });
}

// performer: P (or the button) arms pick mode; the next click on the frame stores the frame shown and the
// clicked pixel of the input video. The image is the upright frame scaled to the stage, so the click is
// scaled back by the video's size over the image's displayed size; a click inside pixel k gives k.
function togglePick() { S.picking = !S.picking; render(); }

function pickPerformer(e) {
  if (!S.picking || !S.vid) return;
  const img = $("frame"), r = img.getBoundingClientRect();
  if (img.dataset.video !== S.vid.id || img.dataset.frame !== String(S.frame) || !r.width || !r.height) {
    flash("wait for the frame to load, then click the performer"); return;
  }
  const px = (v, lo, size, n) => Math.min(n - 1, Math.max(0, Math.floor(((v - lo) / size) * n)));
  const p = { frame: S.frame, x: px(e.clientX, r.left, r.width, S.vid.width),
              y: px(e.clientY, r.top, r.height, S.vid.height) };
  S.picking = false;
  change(() => { marks().performer = p; });
  render(); // also when the same pixel was chosen again (no change): pick mode ends
}

function clearPerformer() { S.picking = false; change(() => { marks().performer = null; }); render(); }

$("frame").addEventListener("click", pickPerformer);

// ------------------------------------------------------------------ saving
async function save() {
  clearTimeout(S.saveTimer);
  if (S.conflict || S.saving || S.changes === S.savedChanges) { setStatus(); return S.changes === S.savedChanges; }
  S.saving = true; setStatus();
  const at = S.changes;
  const sent = baseOf(S.classes, S.marks);
  const body = { revision: S.revision, classes: S.classes,
                 videos: Object.entries(S.marks).map(([id, m]) => ({ id, transitions: m.transitions, segments: m.segments,
                                                                     performer: m.performer || null })) };
  let r;
  try { r = await api("PUT", "/api/annotations", body); } catch (e) { r = { status: 0, data: { error: String(e) } }; }
  S.saving = false;
  if (r.ok) { S.revision = r.data.revision; S.savedChanges = at; S.lastError = null; S.base = sent; S.merges = 0; }
  else if (r.status === 409) {
    // changed elsewhere (another page, another process, the file on disk): reload the current state and
    // keep our changes when they touch other videos (and the class list) than the other change did
    if ((S.merges = (S.merges || 0) + 1) <= 3 && await merge()) { S.lastError = null; setStatus(); return save(); }
    S.conflict = true; S.lastError = r.data && r.data.error;
  }
  else { S.lastError = (r.data && r.data.error) || `save failed (${r.status})`; }
  setStatus();
  if (r.ok && S.changes !== S.savedChanges) S.saveTimer = setTimeout(save, 300);
  return r.ok;
}

// a three-way merge per video (and of the class list) of our changes and theirs since S.base; false when
// both changed the same one (the page then stays in conflict: reload to see theirs)
async function merge() {
  const r = await api("GET", "/api/annotations");
  // the server must have moved on (a 409 at our own revision: the file on disk cannot be used)
  if (!r.ok || !S.base || r.data.revision === S.revision) return false;
  const theirs = marksOf(r.data), base = S.base;
  const merged = {};
  let took = false;
  for (const id of Object.keys(theirs)) {
    const mine = S.marks[id];
    const mineChanged = !mine || canon(mine) !== base.marks[id];
    const theirsChanged = canon(theirs[id]) !== base.marks[id];
    if (mineChanged && theirsChanged && canon(mine) !== canon(theirs[id])) return false;
    merged[id] = theirsChanged ? theirs[id] : mine;
    took = took || theirsChanged;
  }
  const mineC = JSON.stringify(S.classes) !== base.classes, theirsC = JSON.stringify(r.data.classes) !== base.classes;
  if (mineC && theirsC && JSON.stringify(S.classes) !== JSON.stringify(r.data.classes)) return false;
  S.classes = theirsC ? r.data.classes : S.classes;
  S.marks = merged;
  S.revision = r.data.revision;
  S.base = baseOf(r.data.classes, theirs);
  if (took) { S.undo = []; S.redo = []; }  // an undo must not bring back what the other change replaced
  renderClasses(); render();
  return true;
}

function setStatus() {
  const el = $("status");
  let cls, text;
  if (S.conflict) { cls = "conflict"; text = "conflict: changed elsewhere, reload (your edits are not saved)"; }
  else if (S.lastError) { cls = "error"; text = S.lastError; }
  else if (S.saving) { cls = "saving"; text = "saving…"; }
  else if (S.changes !== S.savedChanges) { cls = "dirty"; text = "unsaved"; }
  else { cls = "saved"; text = `saved (revision ${S.revision})`; }
  el.className = cls; el.textContent = text; el.title = text;
}

window.addEventListener("beforeunload", (e) => {
  if (S.changes !== S.savedChanges) { e.preventDefault(); e.returnValue = ""; }
});

// ------------------------------------------------------------------ exchange
$("export").addEventListener("click", async () => {
  await save();
  const a = document.createElement("a");
  a.href = withKey(`/api/export/${$("export-format").value}?video=${S.vid.id}`);
  a.download = "";
  document.body.appendChild(a); a.click(); a.remove();
});

$("import-file").addEventListener("change", async () => {
  const file = $("import-file").files[0];
  if (!file) return;
  const data = await file.arrayBuffer();
  const r = await api("POST", `/api/import/${$("import-format").value}?video=${S.vid.id}`, data, true);
  $("import-file").value = "";
  if (!r.ok) { flash((r.data && r.data.error) || `import failed (${r.status})`); return; }
  change(() => {
    S.classes = r.data.classes;
    // an import brings marks, not a performer choice: the current one is kept
    S.marks[r.data.video] = { transitions: r.data.transitions, segments: r.data.segments,
                              performer: S.marks[r.data.video].performer || null };
  });
  renderClasses();
});

// ------------------------------------------------------------------ keys (CVAT-like)
function typing(e) { const t = e.target; return t && (t.tagName === "INPUT" || t.tagName === "SELECT" || t.tagName === "TEXTAREA"); }

document.addEventListener("keydown", (e) => {
  const k = e.key;
  const ctrl = e.ctrlKey || e.metaKey;
  if (ctrl && (k === "s" || k === "S")) { e.preventDefault(); save(); return; }
  if (k === "Escape") {
    $("help").hidden = true; $("goto-form").hidden = true;
    if (S.picking) { S.picking = false; render(); }
    return;
  }
  if (typing(e)) return;
  if (ctrl && (k === "z" || k === "Z")) { e.preventDefault(); if (e.shiftKey) redo(); else undo(); return; }
  if (ctrl && (k === "y" || k === "Y")) { e.preventDefault(); redo(); return; }
  if (ctrl || e.altKey) return;
  let handled = true;
  if (/^Digit[1-9]$/.test(e.code) && e.shiftKey) { e.preventDefault(); relabelHere(Number(e.code.slice(5)) - 1); return; }
  switch (k) {
    case "f": case "F": case "ArrowRight": go(S.frame + 1); break;
    case "d": case "D": case "ArrowLeft": go(S.frame - 1); break;
    case "v": case "V": go(S.frame + 10); break;
    case "c": case "C": go(S.frame - 10); break;
    case "Home": go(0); break;
    case "End": go(S.vid.frames - 1); break;
    case " ": togglePlay(); break;
    case "`": showGoto(); break;
    case "t": case "T": markTransition(); break;
    case "[": startSegment(); break;
    case "]": endSegment(); break;
    case "p": case "P": togglePick(); break;
    case "Delete": case "Backspace": removeHere(); break;
    case "?": $("help").hidden = !$("help").hidden; break;
    default:
      if (k >= "1" && k <= "9") pickAction(Number(k) - 1);
      else handled = false;
  }
  if (handled) e.preventDefault();
});

function showGoto() {
  const f = $("goto-form");
  f.hidden = false;
  $("goto").max = String(S.vid.frames - 1);
  $("goto").value = String(S.frame);
  $("goto").focus(); $("goto").select();
}
$("goto-form").addEventListener("submit", (e) => {
  e.preventDefault();
  const n = Number($("goto").value);
  $("goto-form").hidden = true;
  $("goto").blur();
  if (Number.isInteger(n)) go(n);
});

$("video").addEventListener("change", () => { selectVideo($("video").value); $("video").blur(); });
$("save").addEventListener("click", () => save());
$("help-button").addEventListener("click", () => { $("help").hidden = !$("help").hidden; });
$("performer-pick").addEventListener("click", () => { togglePick(); $("performer-pick").blur(); });
$("performer-clear").addEventListener("click", () => { clearPerformer(); $("performer-clear").blur(); });
$("performer-info").addEventListener("click", () => { const p = marks().performer; if (p) go(p.frame); });
$("t-status").addEventListener("click", () => change(() => {
  const t = transitionAt(S.frame); if (t) t.status = t.status === "accepted" ? "discarded" : "accepted";
}));
for (const [id, key] of [["t-from", "from_action"], ["t-to", "to_action"]]) {
  $(id).addEventListener("change", () => {
    change(() => { const t = transitionAt(S.frame); if (t) t[key] = $(id).value; });
    $(id).blur();
  });
}

// ------------------------------------------------------------------ drawing
let classIndex = { of: null, map: new Map() };
function color(name) {   // a map of the names, rebuilt when the list changes (indexOf per name: quadratic)
  if (classIndex.of !== S.classes) classIndex = { of: S.classes, map: new Map(S.classes.map((c, k) => [c, k])) };
  const i = classIndex.map.get(name) || 0;
  return `hsl(${(i * 137.5) % 360} 65% 55%)`;
}

function flash(msg) { S.lastError = msg; setStatus(); setTimeout(() => { if (S.lastError === msg) { S.lastError = null; setStatus(); } }, 4000); }

function renderInfo() {
  const ts = S.timestamps[S.vid.id] || [];
  const t = ts[S.frame];
  const shown = $("frame").dataset.frame;
  $("info").textContent = `frame ${S.frame} / ${S.vid.frames - 1}  ·  ${t === undefined ? "" : t.toFixed(3) + " s"}` +
    `  ·  ${S.vid.fps.toFixed(2)} fps${S.vid.constant_rate ? "" : " (variable)"}` +
    (String(S.frame) !== shown ? "  ·  loading" : "") + (S.playing ? "  ·  playing" : "");
}

function renderClasses() {
  const ol = $("classes");
  ol.innerHTML = "";
  S.classes.forEach((c, k) => {
    const li = document.createElement("li");
    li.textContent = (k < 9 ? `${k + 1}  ` : "   ") + c;
    li.style.borderLeftColor = color(c);
    if (k === S.action) li.className = "current";
    li.addEventListener("click", () => pickAction(k));
    ol.appendChild(li);
  });
  for (const id of ["t-from", "t-to"]) {
    const sel = $(id); const v = sel.value; sel.innerHTML = "";
    for (const c of S.classes) { const o = document.createElement("option"); o.value = o.textContent = c; sel.appendChild(o); }
    sel.value = v;
  }
}

function render() {
  if (!S.vid) return;
  renderInfo();
  const pending = S.pending === null ? "" : `segment from ${S.pending}: ] ends it (${actionName()})`;
  $("pending").textContent = pending; $("pending").title = pending;
  renderRecognised();
  renderPerformer();
  const m = marks();
  const segs = $("segments"); segs.innerHTML = "";
  for (const s of m.segments) {
    const li = document.createElement("li");
    li.textContent = `${s.start}–${s.end - 1}  ${s.action}`;
    li.style.borderLeft = `.5em solid ${color(s.action)}`;
    if (s.start <= S.frame && S.frame < s.end) li.className = "here";
    li.addEventListener("click", () => go(s.start));
    segs.appendChild(li);
  }
  const trs = $("transitions"); trs.innerHTML = "";
  for (const t of m.transitions) {
    const li = document.createElement("li");
    li.textContent = `${t.frame}  ${t.from_action} → ${t.to_action}`;
    li.className = (t.frame === S.frame ? "here " : "") + (t.status === "discarded" ? "discarded" : "");
    li.addEventListener("click", () => go(t.frame));
    trs.appendChild(li);
  }
  const t = transitionAt(S.frame);
  $("transition-none").hidden = !!t; $("transition-edit").hidden = !t;
  if (t) {
    $("t-from").value = t.from_action; $("t-to").value = t.to_action;
    $("t-status").textContent = t.status === "accepted" ? "accepted (click: discard)" : "discarded (click: accept)";
    $("t-status").className = t.status;
  }
  renderCandidates(t);
  drawTimeline();
  drawOverlay();
}

// the last index k with sorted[k] <= x (-1 when x is before the first)
function lastAtOrBefore(sorted, x, key) {
  let lo = 0, hi = sorted.length - 1, k = -1;
  while (lo <= hi) {
    const mid = (lo + hi) >> 1;
    if ((key ? key(sorted[mid]) : sorted[mid]) <= x) { k = mid; lo = mid + 1; } else hi = mid - 1;
  }
  return k;
}

// the recognised action (and its confidence, when the file has one) of the current frame, beside the frame
function renderRecognised() {
  const rec = (S.overlays[S.vid.id] || {}).recognized;
  $("recognised-panel").hidden = !rec;
  if (!rec) return;
  const el = $("recognised");
  const k = lastAtOrBefore(rec.spans, S.frame, (s) => s.start);
  const span = k >= 0 && S.frame < rec.spans[k].end ? rec.spans[k] : null;
  el.textContent = span ? span.action : "none (no recognised frame here)";
  el.style.borderLeftColor = span ? color(span.action) : "transparent";
  el.title = `from ${rec.file}`;
  if (span && rec.confidence) {
    const w = lastAtOrBefore(rec.starts, S.frame);
    if (w >= 0) {
      const c = document.createElement("span");
      c.className = "confidence";
      c.textContent = `confidence ${rec.confidence[w].toFixed(2)}`;
      el.appendChild(c);
    }
  }
}

function renderPerformer() {
  const p = marks().performer;
  const info = $("performer-info");
  info.textContent = p ? `frame ${p.frame}, pixel (${+p.x.toFixed(1)}, ${+p.y.toFixed(1)})`
    : "none chosen (pose follows the most prominent person)";
  info.className = p ? "chosen" + (p.frame === S.frame ? " here" : "") : "";
  info.title = p ? "go to that frame" : "";
  $("performer-clear").disabled = !p;
  $("performer-pick").className = S.picking ? "active" : "";
  // the hint stays in the side panel: a longer header could wrap and move the frame under the mouse
  $("performer-pick").textContent = S.picking ? "Click the performer on the frame (Esc cancels)" : "Choose performer";
  $("stage").classList.toggle("picking", S.picking);
}

function renderCandidates(t) {
  const ov = S.overlays[S.vid.id] || {};
  const list = $("candidates"); list.innerHTML = "";
  const cands = (ov.matches && ov.matches.frames[String(S.frame)]) || [];
  $("matches-note").textContent = !ov.matches ? "(no --matches given)" : cands.length ? "" : "(none at this frame)";
  for (const c of cands) {
    const li = document.createElement("li");
    const d = t && (t.candidates || []).find((x) => x.clip === c.clip && x.time === c.time);
    const name = c.clip.split("/").pop();
    li.textContent = `${name} @ ${c.time.toFixed(2)} s` + (c.cost == null ? "" : ` (cost ${c.cost.toFixed(3)})`);
    if (d) { const s = document.createElement("span"); s.className = `${d.status}-mark`; s.textContent = ` ${d.status}`; li.appendChild(s); }
    for (const [label, status] of [["accept", "accepted"], ["discard", "discarded"]]) {
      const b = document.createElement("button");
      b.type = "button"; b.textContent = label; b.disabled = !t;
      b.title = t ? `${label} as an enhancement node` : "mark this frame as a transition first (T)";
      b.addEventListener("click", () => decideCandidate(c, status));
      li.appendChild(b);
    }
    list.appendChild(li);
  }
}

function drawTimeline() {
  const cv = $("timeline");
  const w = cv.clientWidth, h = cv.clientHeight, dpr = window.devicePixelRatio || 1;
  if (cv.width !== Math.round(w * dpr)) { cv.width = Math.round(w * dpr); cv.height = Math.round(h * dpr); }
  const g = cv.getContext("2d");
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, w, h);
  const n = S.vid.frames;
  const x = (f) => (f / n) * w;
  const ov = S.overlays[S.vid.id] || {};
  g.fillStyle = "#333"; g.fillRect(0, 0, w, h);
  if (ov.recognized) {                       // row 1: recognised actions
    for (const s of ov.recognized.spans) { g.fillStyle = color(s.action); g.globalAlpha = 0.55; g.fillRect(x(s.start), 2, Math.max(1, x(s.end) - x(s.start)), 14); }
    g.globalAlpha = 1;
  }
  for (const s of marks().segments) {        // row 2: the user's segments
    g.fillStyle = color(s.action); g.fillRect(x(s.start), 20, Math.max(1, x(s.end) - x(s.start)), 22);
  }
  if (S.pending !== null) {
    const a = Math.min(S.pending, S.frame), b = Math.max(S.pending, S.frame) + 1;
    g.strokeStyle = "#ffcf66"; g.setLineDash([4, 3]); g.strokeRect(x(a), 20, x(b) - x(a), 22); g.setLineDash([]);
  }
  for (const t of marks().transitions) {     // row 3: transition marks
    g.fillStyle = t.status === "accepted" ? "#ffffff" : "#888";
    g.beginPath(); g.moveTo(x(t.frame + 0.5), 44); g.lineTo(x(t.frame + 0.5) - 5, 56); g.lineTo(x(t.frame + 0.5) + 5, 56); g.fill();
    g.fillRect(x(t.frame + 0.5) - 0.5, 18, 1, 26);
  }
  const step = [1, 2, 5, 10, 25, 50, 100, 250, 500, 1000, 2500, 5000, 10000].find((k) => (k / n) * w >= 60) || 25000;
  g.fillStyle = "#aaa"; g.font = "10px sans-serif";   // frame ticks (0-based decoded indices)
  for (let f = 0; f < n; f += step) { g.fillRect(x(f), h - 6, 1, 6); g.fillText(String(f), x(f) + 2, h - 1); }
  const perf = marks().performer;
  if (perf) {                                // the performer choice: a diamond on row 3
    const c = x(perf.frame + 0.5);
    g.fillStyle = PERFORMER;
    g.beginPath(); g.moveTo(c, 44); g.lineTo(c + 5, 50); g.lineTo(c, 56); g.lineTo(c - 5, 50); g.fill();
  }
  g.fillStyle = "#ff4d4d"; g.globalAlpha = 0.7;  // the current frame
  g.fillRect(x(S.frame), 0, Math.max(2, x(S.frame + 1) - x(S.frame)), h - 8);
  g.globalAlpha = 1;
  const leg = $("legend");
  leg.textContent = `timeline: ${ov.recognized ? "top row recognised (" + ov.recognized.file + "), " : ""}` +
    "middle row your segments, ▲ transition marks (grey: discarded), ◆ performer chosen, red line: this frame";
}

function fitFrame() {            // scale the frame to the stage, keeping its aspect ratio
  const img = $("frame"), st = $("stage");
  if (!img.naturalWidth) return;
  const s = Math.min(st.clientWidth / img.naturalWidth, st.clientHeight / img.naturalHeight);
  img.style.width = `${Math.floor(img.naturalWidth * s)}px`;
  img.style.height = `${Math.floor(img.naturalHeight * s)}px`;
}

function drawOverlay() {
  const img = $("frame"), cv = $("overlay");
  const ov = S.overlays[S.vid && S.vid.id] || {};
  const r = img.getBoundingClientRect(), pr = img.parentElement.getBoundingClientRect();
  cv.style.left = `${r.left - pr.left}px`; cv.style.top = `${r.top - pr.top}px`;
  cv.width = Math.max(1, Math.round(r.width)); cv.height = Math.max(1, Math.round(r.height));
  const g = cv.getContext("2d");
  g.clearRect(0, 0, cv.width, cv.height);
  const shown = img.dataset.frame;
  if (!img.naturalWidth || shown === undefined || !S.vid || img.dataset.video !== S.vid.id) return;
  const sx = cv.width / img.naturalWidth, sy = cv.height / img.naturalHeight;
  const pose = ov.poses && ov.poses.frames[shown];
  if (pose) {
    g.lineWidth = 3; g.strokeStyle = "#39e639"; g.fillStyle = "#ffe14d";
    for (const [a, b] of ov.poses.edges) {
      const p = pose.points[a], q = pose.points[b];
      g.beginPath(); g.moveTo(p[0] * sx, p[1] * sy); g.lineTo(q[0] * sx, q[1] * sy); g.stroke();
    }
    for (const p of pose.points) { g.beginPath(); g.arc(p[0] * sx, p[1] * sy, 3.5, 0, 2 * Math.PI); g.fill(); }
    if (pose.viewpoint) { g.font = "14px sans-serif"; g.fillText(pose.viewpoint, 6, cv.height - 8); }
  }
  const perf = marks().performer;
  if (perf && String(perf.frame) === shown) {  // the chosen pixel's centre (pixel centres at integers)
    const cx = (perf.x + 0.5) * sx, cy = (perf.y + 0.5) * sy;
    g.lineWidth = 5; g.strokeStyle = "#000";
    g.beginPath(); g.arc(cx, cy, 10, 0, 2 * Math.PI); g.stroke();
    g.lineWidth = 3; g.strokeStyle = PERFORMER;
    g.beginPath(); g.arc(cx, cy, 10, 0, 2 * Math.PI); g.stroke();
    g.beginPath(); g.moveTo(cx - 16, cy); g.lineTo(cx - 4, cy); g.moveTo(cx + 4, cy); g.lineTo(cx + 16, cy);
    g.moveTo(cx, cy - 16); g.lineTo(cx, cy - 4); g.moveTo(cx, cy + 4); g.lineTo(cx, cy + 16); g.stroke();
    g.font = "13px sans-serif"; g.fillStyle = PERFORMER;   // the label inside the frame, near the ring
    const right = cx + 80 < cv.width;
    g.textAlign = right ? "left" : "right";
    g.fillText("performer", right ? cx + 13 : cx - 13, cy > 24 ? cy - 13 : cy + 24);
    g.textAlign = "left";
  }
}

$("timeline").addEventListener("click", (e) => {
  const r = $("timeline").getBoundingClientRect();
  go(Math.floor(((e.clientX - r.left) / r.width) * S.vid.frames));
});
window.addEventListener("resize", () => { if (S.vid) { fitFrame(); drawTimeline(); drawOverlay(); } });

load().catch((e) => { $("info").textContent = `cannot load: ${e}`; });
