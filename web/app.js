// SPDX-License-Identifier: MIT
// The page of `uvr view` (docs/VIEWER.md is its contract): one WebSocket to the server, the
// frames it sends drawn on a canvas, the mouse driving the camera, the sidebar the rest of the
// session state. The local `state` is the server's last word plus the edits sent since; every
// edit is sent as a `set` with the full value of each key it changes.

import * as cam from "./camera.js";
import {colorAt, css} from "./colormap.js";
import {TfEditor, isoText, parseIso} from "./tf_editor.js";

const $ = (id) => document.getElementById(id);

const kSizes = [[512, 512], [768, 768], [1024, 1024]];
const kWheelSettleMs = 150;     // a final camera this long after the last wheel event
const kExportRefreshMs = 400;   // the command field is refreshed this long after a final change
const kErrorShowMs = 6000;      // the error line fades out after this
const kPingMs = 30000;          // keep-alive through tunnels and proxies

// ---- Session ---------------------------------------------------------------------------------

const session = {
    ws: null,
    connected: false,
    info: null,
    state: null,
    histogram: null,
    seq: 0,                // last `seq` sent
    lastFrame: null,       // metadata of the last frame received (+ bytes, hash, received)
    frameCount: 0,         // frames received (binary images, not snapshots)
    framesDecoded: 0,      // frames whose decoding ended (drawn, or overtaken by a newer one)
    lastError: null,
    errorCount: 0,
    counts: {},            // messages received, by type
    header: null,          // the text message the next binary message belongs to
    frameTimes: [],        // arrival times (ms) of recent frames, for the FPS figure
    lastExport: null,
    exportFresh: false,    // lastExport describes the current state
    exportWaiters: [],     // {then, quiet} for the next `export` replies, in order
    lastPong: null,
    sentSteps: [],         // [seq, step] of the sets that changed the time step, oldest first
    shownStep: null,       // the time step of the frame on the canvas (null: the state's)
};

const token = new URLSearchParams(location.search).get("token") || "";

function send(message) {
    if (!session.ws || session.ws.readyState !== WebSocket.OPEN) return false;
    session.ws.send(JSON.stringify(message));
    return true;
}

// The session-state keys the page keeps a local copy of.
const kStateKeys = ["camera", "tf", "range", "field", "method", "quality", "heatmap", "size",
                    "opacity_unit", "opacity_law", "step", "clip_planes", "shade", "ambient",
                    "diffuse", "specular", "specular_power", "normals", "iso", "clip_surface",
                    "gradient_opacity", "background"];

// Gradient shading's coefficients: the slider's id and the setting it sets.
const kLightSliders = [["ambient", "ambient"], ["diffuse", "diffuse"], ["specular", "specular"],
                       ["specular-power", "specular_power"]];

/// Sends a `set` changing `changes` (state keys with full values, plus `preset` or
/// `colormap_json`), applies the state keys locally and returns its seq.
function sendSet(changes, interactive = false) {
    const seq = ++session.seq;
    const message = {type: "set", seq, interactive, ...changes};
    if (!send(message)) return seq;
    if ("step" in changes) {
        session.sentSteps.push([seq, changes.step]);
        if (session.sentSteps.length > 64) session.sentSteps.shift();
    }
    for (const k of kStateKeys) {
        if (k in changes && session.state) session.state[k] = structuredClone(changes[k]);
    }
    session.exportFresh = false;
    if (!interactive) scheduleExportRefresh();
    updateControls();
    return seq;
}

// ---- Connection ------------------------------------------------------------------------------

function connect() {
    if (!token) {
        showError("This page's address has no ?token=: open the URL that `uvr view` printed.");
        showBanner("No access token in the address.");
        return;
    }
    const scheme = location.protocol === "https:" ? "wss:" : "ws:";
    const ws = new WebSocket(`${scheme}//${location.host}/ws?token=${encodeURIComponent(token)}`);
    ws.binaryType = "arraybuffer";
    session.ws = ws;
    ws.addEventListener("open", () => {
        session.connected = true;
    });
    ws.addEventListener("message", (e) => onMessage(e.data));
    ws.addEventListener("close", () => {
        session.connected = false;
        showBanner("Connection to the uvr server lost.");
    });
    setInterval(() => send({type: "ping", seq: 0}), kPingMs);
}

function onMessage(data) {
    if (typeof data !== "string") {
        onBinary(data);
        return;
    }
    let m;
    try {
        m = JSON.parse(data);
    } catch {
        console.warn("uvr view: a message that is not JSON", data.slice(0, 200));
        return;
    }
    session.counts[m.type] = (session.counts[m.type] || 0) + 1;
    switch (m.type) {
        case "info": onInfo(m); break;
        case "state": onState(m.state && typeof m.state === "object" ? m.state : m); break;
        case "histogram": onHistogram(m); break;
        case "frame":
        case "snapshot": session.header = m; break;
        case "export": onExport(m); break;
        case "progress": onProgress(m); break;
        case "prepared": onPrepared(m); break;
        case "error": onServerError(m); break;
        case "pong": session.lastPong = m; break;
        default: console.warn("uvr view: unknown message type", m.type);
    }
}

function onBinary(buffer) {
    const header = session.header;
    session.header = null;
    if (!header) {
        console.warn("uvr view: an image without its description");
        return;
    }
    if (header.type === "snapshot") {
        download(new Blob([buffer], {type: "image/png"}), "uvr-view.png");
        return;
    }
    const now = performance.now();
    session.frameCount++;
    session.frameTimes.push(now);
    session.lastFrame = {...header, bytes: buffer.byteLength, hash: fnv1a(buffer), received: now};
    updateFrameStats(header);
    hideProgressIfDone();
    drawFrame(header, buffer);
}

/// FNV-1a hash of the bytes, as hex: lets a test tell frames apart without shipping them.
function fnv1a(buffer) {
    const bytes = new Uint8Array(buffer);
    let h = 0x811c9dc5;
    for (let i = 0; i < bytes.length; i++) {
        h ^= bytes[i];
        h = Math.imul(h, 0x01000193);
    }
    return (h >>> 0).toString(16).padStart(8, "0");
}

function onInfo(m) {
    session.info = m;
    fitView = !!m.fit_size;
    session.state = structuredClone(m.state);
    session.histogram = m.histogram || null;
    tfEditor.update({histogram: session.histogram});
    $("title-file").textContent = m.file || "";
    $("title-file").title = m.file || "";
    fillMeshInfo(m);
    fillSelectors(m);
    resizeCanvas(session.state.size);
    updateControls();
    scheduleExportRefresh();
    fitSize();
}

function onState(state) {
    const next = {};
    for (const k of kStateKeys) if (k in state) next[k] = state[k];
    session.state = {...(session.state || {}), ...structuredClone(next)};
    session.exportFresh = false;
    hideProgress();
    updateControls();
    scheduleExportRefresh();
}

/// The server finished preparing the mesh after this page connected: the mesh panel's
/// tetrahedra, preparation time and device.
function onPrepared(m) {
    if (!session.info) return;
    for (const k of ["tetrahedra", "rendered_cells", "prepare_seconds", "device"])
        if (k in m) session.info[k] = m[k];
    fillMeshInfo(session.info);
    hideProgress();
}

function onHistogram(m) {
    session.histogram = m;
    tfEditor.update({histogram: m});
}

// ---- The image -------------------------------------------------------------------------------

const view = $("view");
const viewContext = view.getContext("2d");
let shownBitmap = null;   // the bitmap on the canvas, kept to redraw it after a resize
let decodeCounter = 0;    // frames sent to the decoder
let drawnDecode = 0;      // the newest of them drawn: an older decode finishing late is dropped

async function drawFrame(header, buffer) {
    const id = ++decodeCounter;
    let bitmap;
    try {
        const type = header.format === "jpeg" ? "image/jpeg" : "image/png";
        bitmap = await createImageBitmap(new Blob([buffer], {type}));
    } catch (e) {
        session.framesDecoded++;
        showError(`could not decode a ${header.format} frame: ${e.message || e}`);
        return;
    }
    session.framesDecoded++;
    if (id < drawnDecode) {
        bitmap.close();
        return;
    }
    drawnDecode = id;
    if (shownBitmap) shownBitmap.close();
    shownBitmap = bitmap;
    // The time label follows the frames shown, not the steps asked for.
    let shown = null;
    for (const [seq, step] of session.sentSteps) if (seq <= (header.seq ?? 0)) shown = step;
    if (shown !== null && shown !== session.shownStep) {
        session.shownStep = shown;
        fillTime((session.state && session.state.step) || 0);
    }
    resizeCanvas(fullSize(header));
    paint();
}

/// Draws the shown frame over the whole canvas: a reduced-resolution frame is scaled up to the
/// full size (the canvas holds the state's full-resolution pixels).
function paint() {
    viewContext.clearRect(0, 0, view.width, view.height);
    drawAnnotations();
    if (!shownBitmap) return;
    viewContext.imageSmoothingEnabled = true;
    viewContext.imageSmoothingQuality = "high";
    viewContext.drawImage(shownBitmap, 0, 0, view.width, view.height);
}

// ---- Annotations: scalar bar, orientation axes, outline (drawn over the image on a canvas of
// their own; the saved PNG is the volume over the background, as `uvr render` writes it) -----

const overlay = $("overlay");
const overlayContext = overlay.getContext("2d");
// ParaView's orientation axes colours: x red, y yellow, z green.
const kAxisColors = ["#e8413c", "#f2d64b", "#4fc35a"];

/// Redraws the annotations the View section turns on, for the local state's camera and map.
function drawAnnotations() {
    const g = overlayContext, w = overlay.width, h = overlay.height;
    g.clearRect(0, 0, w, h);
    const s = session.state;
    if (!s || !s.camera) return;
    const unit = window.devicePixelRatio || 1;  // one CSS pixel
    if ($("show-outline").checked) drawOutline(g, s.camera, w, h, unit);
    if ($("show-axes").checked) drawAxes(g, s.camera, h, unit);
    if (s.heatmap) drawHeatmapScale(g, w, h, unit);
    else if ($("show-scalar-bar").checked && s.tf && s.range) drawScalarBar(g, s, w, h, unit);
}

// The heat map's colour bar (render/heatmap.cpp: kHeatmapLegendWidth pixels at the image's right,
// the bar from kBarGap, kBarMarginY from the top and bottom) carries no numbers: the page writes
// its scale, 0 to the frame's largest samples per pixel, beside it.
const kHeatmapLegend = {width: 40, gap: 8, marginY: 8};

function drawHeatmapScale(g, w, h, unit) {
    const frame = session.lastFrame;
    const top = frame && frame.stats && frame.stats.max_samples_per_pixel;
    if (!Number.isFinite(top) || view.width <= kHeatmapLegend.width) return;
    const sx = w / view.width, sy = h / view.height;
    const margin = view.height >= 3 * kHeatmapLegend.marginY ? kHeatmapLegend.marginY : 0;
    const x = (view.width - kHeatmapLegend.width + kHeatmapLegend.gap) * sx - 4 * unit;
    const yTop = margin * sy, yBottom = (view.height - 1 - margin) * sy;
    g.font = `${Math.round(11 * unit)}px sans-serif`;
    g.textAlign = "right";
    g.textBaseline = "middle";
    const mid = Math.floor(top / 2);
    const ticks = [[top, yTop], [0, yBottom]];
    if (mid > 0 && mid < top) ticks.push([mid, yBottom - (mid / top) * (yBottom - yTop)]);
    for (const [v, y] of ticks) {
        const text = String(v);
        const tw = g.measureText(text).width;
        g.fillStyle = "rgba(0, 0, 0, 0.6)";
        g.fillRect(x - tw - 3 * unit, y - 7 * unit, tw + 6 * unit, 14 * unit);
        g.fillStyle = "#fff";
        g.fillText(text, x, y);
    }
    g.textAlign = "right";
    g.textBaseline = "bottom";
    g.fillStyle = "#fff";
    g.fillText("samples / pixel", x, Math.max(12 * unit, yTop - 2 * unit));
}

function drawOutline(g, camera, w, h, unit) {
    const [lo, hi] = meshBounds();
    const corner = (i) => [i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]];
    g.strokeStyle = "rgba(255, 255, 255, 0.7)";
    g.lineWidth = unit;
    g.beginPath();
    for (let i = 0; i < 8; i++)
        for (const bit of [1, 2, 4]) {
            if (i & bit) continue;
            const a = cam.project(camera, corner(i), w, h);
            const b = cam.project(camera, corner(i | bit), w, h);
            if (!a || !b) continue;  // an edge reaching behind the camera
            g.moveTo(a[0], a[1]);
            g.lineTo(b[0], b[1]);
        }
    g.stroke();
}

function drawAxes(g, camera, h, unit) {
    const f = cam.frame(camera);
    const length = 28 * unit, cx = 44 * unit, cy = h - 44 * unit;
    // Farthest first, so the nearer axes are drawn over it.
    const axes = [0, 1, 2].map((a) => {
        const e = [0, 1, 2].map((i) => (i === a ? 1 : 0));
        return {a, x: cam.dot(e, f.right), y: cam.dot(e, f.up), z: cam.dot(e, f.dir)};
    }).sort((p, q) => q.z - p.z);
    g.font = `bold ${Math.round(11 * unit)}px sans-serif`;
    g.textAlign = "center";
    g.textBaseline = "middle";
    g.lineWidth = 2 * unit;
    for (const {a, x, y} of axes) {
        const ex = cx + x * length, ey = cy - y * length;
        g.strokeStyle = g.fillStyle = kAxisColors[a];
        g.beginPath();
        g.moveTo(cx, cy);
        g.lineTo(ex, ey);
        g.stroke();
        g.fillText("XYZ"[a], cx + x * (length + 9 * unit), cy - y * (length + 9 * unit));
    }
}

function drawScalarBar(g, s, w, h, unit) {
    const barW = 14 * unit, barH = Math.min(0.5 * h, 240 * unit);
    const x = w - barW - 56 * unit, y = 0.5 * (h - barH);
    const rows = Math.max(2, Math.round(barH));
    for (let i = 0; i < rows; i++) {
        const t = 1 - i / (rows - 1);  // the range's top at the bar's top
        g.fillStyle = css(colorAt(s.tf.colors, s.tf.color_space, t));
        g.fillRect(x, y + (i / rows) * barH, barW, barH / rows + 1);
    }
    g.strokeStyle = "rgba(255, 255, 255, 0.8)";
    g.lineWidth = unit;
    g.strokeRect(x, y, barW, barH);
    g.fillStyle = "#fff";
    g.font = `${Math.round(11 * unit)}px sans-serif`;
    g.textAlign = "left";
    g.textBaseline = "middle";
    g.fillText(fmt(s.range[1], 4), x + barW + 4 * unit, y);
    g.fillText(fmt(s.range[0], 4), x + barW + 4 * unit, y + barH);
    g.textAlign = "center";
    g.textBaseline = "bottom";
    const fields = (session.info && session.info.fields) || [];
    const field = s.field || (fields.find((f) => f.default) || {}).name || "";
    if (field) g.fillText(field, x + 0.5 * barW, y - 6 * unit);
}

for (const id of ["show-scalar-bar", "show-axes", "show-outline"])
    $(id).addEventListener("change", drawAnnotations);

/// The full-resolution size of a frame: a reduced frame's size times its reduction factor (a
/// whole number, found from the heights). Not simply the state's size: a heat map may carry a
/// legend that widens the image.
function fullSize(header) {
    const k = Math.max(1, Math.round(session.state.size[1] / header.height));
    return [header.width * k, header.height * k];
}

/// Gives the canvas `size` (when given) and fits it, with that aspect, into its area.
function resizeCanvas(size) {
    if (size && (view.width !== size[0] || view.height !== size[1])) {
        view.width = size[0];
        view.height = size[1];
        paint();
    }
    const wrap = $("view-wrap");
    const style = getComputedStyle(wrap);
    const px = (v) => parseFloat(v) || 0;
    const availW = wrap.clientWidth - px(style.paddingLeft) - px(style.paddingRight);
    const availH = wrap.clientHeight - px(style.paddingTop) - px(style.paddingBottom);
    const s = Math.max(0, Math.min(availW / view.width, availH / view.height));
    view.style.width = `${Math.floor(view.width * s)}px`;
    view.style.height = `${Math.floor(view.height * s)}px`;
    // The annotations' canvas exactly over the image, at the screen's pixels (their text and
    // lines keep their size whatever the image's resolution).
    const dpr = window.devicePixelRatio || 1;
    const ow = Math.max(1, Math.round(view.width * s * dpr));
    const oh = Math.max(1, Math.round(view.height * s * dpr));
    overlay.style.left = `${view.offsetLeft}px`;
    overlay.style.top = `${view.offsetTop}px`;
    overlay.style.width = view.style.width;
    overlay.style.height = view.style.height;
    if (overlay.width !== ow || overlay.height !== oh) {
        overlay.width = ow;
        overlay.height = oh;
        drawAnnotations();
    }
}
new ResizeObserver(() => resizeCanvas()).observe($("view-wrap"));

// ---- Mouse: the trackball --------------------------------------------------------------------

let drag = null;          // {mode: "rotate" | "pan" | "zoom", x, y, pointerId}
let cameraFrame = 0;      // requestAnimationFrame id of a pending interactive camera message
let wheelTimer = 0;

function scheduleCameraSend() {
    if (cameraFrame) return;
    cameraFrame = requestAnimationFrame(() => {
        cameraFrame = 0;
        sendSet({camera: session.state.camera}, true);
    });
}

function finalCamera() {
    if (cameraFrame) cancelAnimationFrame(cameraFrame);
    cameraFrame = 0;
    sendSet({camera: session.state.camera}, false);
}

view.addEventListener("pointerdown", (e) => {
    if (!session.state || drag) return;
    let mode = null;
    const clipDrag = e.altKey || (e.ctrlKey && e.shiftKey);
    if (e.button === 0 && clipDrag) mode = clipAxis() >= 0 ? "clip" : null;
    else if (e.button === 0) mode = e.shiftKey ? "pan" : e.ctrlKey ? "zoom" : "rotate";
    else if (e.button === 1) mode = "pan";
    else if (e.button === 2) mode = "zoom";
    if (!mode) return;
    e.preventDefault();
    view.focus();
    view.setPointerCapture(e.pointerId);
    view.classList.add("dragging");
    drag = {mode, x: e.clientX, y: e.clientY, pointerId: e.pointerId, moved: false};
});

view.addEventListener("pointermove", (e) => {
    if (!drag || e.pointerId !== drag.pointerId) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (dx === 0 && dy === 0) return;
    drag.x = e.clientX;
    drag.y = e.clientY;
    drag.moved = true;
    const w = view.clientWidth, h = view.clientHeight;
    if (drag.mode === "clip") {
        moveClipPlane(dx, dy, h);
        return;
    }
    let c = session.state.camera;
    if (drag.mode === "rotate") {
        const r = cam.dragRotation(dx, dy, w, h);
        c = cam.orbit(c, r.azimuth, r.elevation);
    } else if (drag.mode === "pan") {
        c = cam.pan(c, dx, dy, h);
    } else {
        c = cam.dolly(c, cam.dragZoomFactor(dy, h));
    }
    session.state.camera = c;
    scheduleCameraSend();
});

function endDrag(e) {
    if (!drag || e.pointerId !== drag.pointerId) return;
    if (view.hasPointerCapture(e.pointerId)) view.releasePointerCapture(e.pointerId);
    view.classList.remove("dragging");
    const {moved, mode} = drag;
    drag = null;
    if (moved && mode === "clip") sendSet({clip_planes: session.state.clip_planes});
    else if (moved) finalCamera();
}
view.addEventListener("pointerup", endDrag);
view.addEventListener("pointercancel", endDrag);
view.addEventListener("contextmenu", (e) => e.preventDefault());
// Keep the middle button from starting the browser's autoscroll.
view.addEventListener("mousedown", (e) => {
    if (e.button === 1) e.preventDefault();
});

view.addEventListener("wheel", (e) => {
    if (!session.state) return;
    e.preventDefault();
    // Notches: Chrome and Firefox give 100 pixels or 3 lines per notch of a mouse wheel.
    const notches = e.deltaMode === 1 ? e.deltaY / 3
                  : e.deltaMode === 2 ? e.deltaY * 10
                  : e.deltaY / 100;
    session.state.camera = cam.dolly(session.state.camera, cam.wheelZoomFactor(notches));
    scheduleCameraSend();
    clearTimeout(wheelTimer);
    wheelTimer = setTimeout(finalCamera, kWheelSettleMs);
}, {passive: false});

for (const b of document.querySelectorAll("button.axis")) {
    b.addEventListener("click", () => send({type: "reset_camera", axis: b.dataset.axis}));
}
$("reset-camera").addEventListener("click", () => send({type: "reset_camera"}));

// ---- Sidebar controls ------------------------------------------------------------------------

const tfEditor = new TfEditor($("tf-canvas"), (opacity, interactive) => {
    sendSet({tf: {...session.state.tf, opacity}}, interactive);
}, (iso, interactive) => sendSet({iso}, interactive));

/// A field spec split into its parts: name, association (point/cell) and component
/// (magnitude/x/y/z/N), as `--field` reads NAME[:point|:cell][:magnitude|:x|:y|:z|:N].
function parseFieldSpec(spec) {
    const parts = String(spec).split(":");
    const out = {name: parts[0], association: null, component: null};
    for (const p of parts.slice(1)) {
        if (p === "point" || p === "cell") out.association = p;
        else out.component = p;
    }
    return out;
}

/// The field selector's entries: a scalar as NAME, a vector as NAME:magnitude, NAME:x, ... (x, y,
/// z for three components, else their numbers); a name used by both point and cell data carries
/// its association.
function fieldEntries(fields) {
    const entries = [];
    for (const f of fields) {
        const shared = fields.filter((g) => g.name === f.name).length > 1;
        const base = shared ? `${f.name}:${f.association}` : f.name;
        if (!(f.components > 1)) {
            entries.push({spec: base, label: `${f.name} (${f.association})`, field: f});
            continue;
        }
        const comps = f.components === 3 ? ["x", "y", "z"]
                                         : [...Array(f.components).keys()].map(String);
        for (const c of ["magnitude", ...comps]) {
            entries.push({spec: `${base}:${c}`, label: `${f.name} · ${c} (${f.association})`,
                          field: f});
        }
    }
    return entries;
}

/// The entry of the selector the state's field spec names (the server may spell a default
/// association or component out, or leave it out).
function matchField(entries, spec) {
    const want = parseFieldSpec(spec);
    const exact = entries.find((e) => e.spec === spec);
    if (exact) return exact;
    return entries.find((e) => {
        const f = e.field, have = parseFieldSpec(e.spec);
        if (f.name !== want.name) return false;
        if (want.association && want.association !== f.association) return false;
        const comp = want.component || (f.components > 1 ? "magnitude" : null);
        return (have.component || null) === comp;
    }) || null;
}

let fieldList = [];

function fillSelectors(info) {
    fieldList = fieldEntries(info.fields || []);
    const field = $("field");
    field.replaceChildren(...fieldList.map((e) => new Option(e.label, e.spec)));
    // The library's settings vocabulary: choices, ranges and docs of the controls.
    const setting = (name) => (info.settings || []).find((d) => d.name === name) || {};
    for (const [id, name] of [["method", "method"], ["opacity-law", "opacity_law"],
                              ["normals", "normals"]]) {
        const d = setting(name);
        const choices = d.choices || (name === "method" ? info.methods : []) || [];
        if (choices.length) $(id).replaceChildren(...choices.map((c) => new Option(c, c)));
        if (d.doc) $(id).closest("label").title = d.doc;
    }
    const quality = setting("quality");
    if (Number.isFinite(quality.min) && Number.isFinite(quality.max)) {
        $("quality").min = sliderFromQuality(quality.min);
        $("quality").max = sliderFromQuality(quality.max);
    }
    if (quality.doc) $("quality").closest("label").title = quality.doc;
    // The shading controls' ranges and docs.
    const shade = setting("shade");
    if (shade.doc) $("shade").closest("label").title = shade.doc;
    for (const [id, name] of kLightSliders) {
        const d = setting(name);
        if (Number.isFinite(d.min)) $(id).min = d.min;
        if (Number.isFinite(d.max)) $(id).max = d.max;
        if (d.doc) $(id).closest("label").title = d.doc;
    }
    const preset = $("preset");
    preset.replaceChildren(...(info.presets || []).map((p) => new Option(p, p)));
    const limits = info.limits || {};
    for (const id of ["size-w", "size-h"]) {
        if (limits.min_size) $(id).min = limits.min_size;
        if (limits.max_size) $(id).max = limits.max_size;
    }
}

const fmt = (v, digits = 6) => (Number.isFinite(v) ? String(Number(v.toPrecision(digits))) : "–");

// Quality: the slider runs over -log10(1 - q), so 0.99, 0.999 and 0.9999 are as far apart as
// 0.9 and 0.99.
const qualityFromSlider = (u) => Math.round((1 - Math.pow(10, -u)) * 1e4) / 1e4;
const sliderFromQuality = (q) => -Math.log10(Math.max(1e-4, 1 - q));

/// Shows the local state in every control (the one being dragged keeps the user's value).
function updateControls() {
    const s = session.state;
    if (!s) return;
    // Field: an unknown spelling gets its own entry rather than showing a wrong field.
    const field = $("field");
    const entry = matchField(fieldList, s.field);
    if (entry) {
        field.value = entry.spec;
    } else if (s.field) {
        if (![...field.options].some((o) => o.value === s.field)) {
            field.add(new Option(s.field, s.field));
        }
        field.value = s.field;
    }
    $("method").value = s.method;
    const adaptive = s.method === "adaptive";
    $("quality").disabled = !adaptive;
    if (document.activeElement !== $("quality")) $("quality").value = sliderFromQuality(s.quality);
    $("quality-value").textContent = fmt(s.quality, 4);
    if (s.opacity_law) $("opacity-law").value = s.opacity_law;
    $("heatmap").checked = !!s.heatmap;
    $("shade").checked = !!s.shade;
    // The coefficients light the volume when shaded, and isosurfaces and the cut face always.
    const lit = !!s.shade || (s.iso || []).length > 0 ||
                (!!s.clip_surface && (s.clip_planes || []).length > 0);
    // The normals' gradients are the gradient opacity's too.
    $("normals").disabled = !lit && !s.gradient_opacity;
    if (s.normals) $("normals").value = s.normals;
    if (document.activeElement !== $("gradient-opacity"))
        $("gradient-opacity").value = s.gradient_opacity || "";
    $("clip-surface").checked = !!s.clip_surface;
    for (const [id, name] of kLightSliders) {
        $(id).disabled = !lit;  // read only then
        if (!Number.isFinite(s[name])) continue;
        if (document.activeElement !== $(id)) $(id).value = s[name];
        $(`${id}-value`).textContent = fmt(s[name], 3);
    }
    fillClip(s.clip_planes || []);
    fillIso(s.iso || []);
    fillTime(s.step || 0);
    fillSizes(s.size);
    // Transfer function.
    const preset = $("preset");
    const name = s.tf && s.tf.name;
    if (name && ![...preset.options].some((o) => o.value === name)) {
        [...preset.options].filter((o) => o.dataset.custom).forEach((o) => o.remove());
        const o = new Option(`${name} (imported)`, name);
        o.dataset.custom = "1";
        preset.add(o, 0);
    }
    preset.value = name || "";
    $("log-scale").checked = !!(s.tf && s.tf.log);
    ["range-lo", "range-hi"].forEach((id, i) => {
        const input = $(id);
        input.dataset.shown = fmt(s.range[i]);
        if (document.activeElement !== input) input.value = input.dataset.shown;
    });
    tfEditor.update({tf: s.tf, range: s.range, isos: s.iso || []});
    // View.
    if (Array.isArray(s.background) && document.activeElement !== $("background"))
        $("background").value = hexColor(s.background);
    if (s.camera) $("parallel").checked = !!s.camera.parallel;
    drawAnnotations();
}

const hexColor = (rgb) => "#" + rgb.map((c) => Math.round(Math.min(1, Math.max(0, c)) * 255)
                                                .toString(16).padStart(2, "0")).join("");
const rgbColor = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255);

$("background").addEventListener("input", (e) => sendSet({background: rgbColor(e.target.value)}, true));
$("background").addEventListener("change", (e) => sendSet({background: rgbColor(e.target.value)}));
$("parallel").addEventListener("change", (e) => {
    if (!session.state) return;
    sendSet({camera: cam.withProjection(session.state.camera, e.target.checked)});
});

/// Opacity curves over the range (the opacity points' [t, alpha], t from 0 to 1), as ParaView's
/// editor makes them.
const kOpacityPresets = {
    "ramp": [[0, 0], [1, 1]],
    "ramp-down": [[0, 1], [1, 0]],
    "constant": [[0, 0.2], [1, 0.2]],
    "step": [[0, 0], [0.499, 0], [0.5, 1], [1, 1]],
    "band": [[0, 0], [0.4, 0], [0.5, 1], [0.6, 0], [1, 0]],
    "edges": [[0, 1], [0.2, 0], [0.8, 0], [1, 1]],
};
$("opacity-preset").addEventListener("change", (e) => {
    const points = kOpacityPresets[e.target.value];
    e.target.value = "";
    if (!points || !session.state || !session.state.tf) return;
    sendSet({tf: {...session.state.tf, opacity: points.map((p) => [...p])}});
});

function fillSizes(size) {
    const select = $("size");
    const key = `${size[0]}x${size[1]}`;
    const sizes = kSizes.map(([w, h]) => `${w}x${h}`);
    // The command line's size and the current one stay offered.
    const start = session.info && session.info.state && session.info.state.size;
    for (const k of [start ? `${start[0]}x${start[1]}` : null, key])
        if (k && !sizes.includes(k)) sizes.unshift(k);
    const wanted = ["fit", ...sizes, "custom"];
    const have = [...select.options].map((o) => o.value);
    if (wanted.join() !== have.join()) {
        select.replaceChildren(...wanted.map((v) => new Option(
            v === "custom" ? "custom…" : v === "fit" ? "fit the view" : v.replace("x", " × "),
            v)));
    }
    if (fitView) select.value = "fit";
    else if (select.value !== "custom" || $("size-custom").hidden) select.value = key;
    $("size-w").placeholder = size[0];
    $("size-h").placeholder = size[1];
}

$("field").addEventListener("change", (e) => {
    // The server re-prepares if needed and answers with `state` (the new field's range).
    sendSet({field: e.target.value});
});
$("method").addEventListener("change", (e) => sendSet({method: e.target.value}));
$("opacity-law").addEventListener("change", (e) => sendSet({opacity_law: e.target.value}));

let qualityFrame = 0;
$("quality").addEventListener("input", (e) => {
    const q = qualityFromSlider(Number(e.target.value));
    $("quality-value").textContent = fmt(q, 4);
    session.state.quality = q;
    if (!qualityFrame) {
        qualityFrame = requestAnimationFrame(() => {
            qualityFrame = 0;
            sendSet({quality: session.state.quality}, true);
        });
    }
});
$("quality").addEventListener("change", (e) => {
    if (qualityFrame) cancelAnimationFrame(qualityFrame);
    qualityFrame = 0;
    sendSet({quality: qualityFromSlider(Number(e.target.value))});
});
$("heatmap").addEventListener("change", (e) => sendSet({heatmap: e.target.checked}));

// ---- Shading: the checkbox and the coefficients' sliders (a frame per animation frame while
// dragged, a full one on release)

$("shade").addEventListener("change", (e) => sendSet({shade: e.target.checked}));
$("normals").addEventListener("change", (e) => sendSet({normals: e.target.value}));
// The server checks the text; a bad one comes back as an error and the state keeps the last.
$("gradient-opacity").addEventListener("change", (e) =>
    sendSet({gradient_opacity: e.target.value.trim()}));
for (const [id, name] of kLightSliders) {
    let pending = 0;
    $(id).addEventListener("input", (e) => {
        const v = Number(e.target.value);
        $(`${id}-value`).textContent = fmt(v, 3);
        session.state[name] = v;
        if (!pending) {
            pending = requestAnimationFrame(() => {
                pending = 0;
                sendSet({[name]: session.state[name]}, true);
            });
        }
    });
    $(id).addEventListener("change", (e) => {
        if (pending) cancelAnimationFrame(pending);
        pending = 0;
        sendSet({[name]: Number(e.target.value)});
    });
}

// ---- Clipping: one plane across an axis (the state holds up to six, from the command line too)

/// The mesh's bounds from `info` ([[x0, y0, z0], [x1, y1, z1]]), or the unit box.
function meshBounds() {
    const b = session.info && session.info.bounds;
    return b && b.length === 2 ? b : [[0, 0, 0], [1, 1, 1]];
}

/// The clip plane the controls describe: through the slider's fraction of the bounds along the
/// axis, keeping the side above it (below it with flip); none when the axis is off.
function clipPlanesFromControls() {
    const axis = $("clip-axis").value;
    if (axis === "") return [];
    const a = Number(axis), [lo, hi] = meshBounds();
    const origin = [0, 0, 0], normal = [0, 0, 0];
    origin[a] = lo[a] + Number($("clip-pos").value) * (hi[a] - lo[a]);
    normal[a] = $("clip-flip").checked ? -1 : 1;
    return [[...origin, ...normal]];
}

/// Shows the state's clip planes: one across an axis in the controls, anything else as "custom".
function fillClip(planes) {
    const axis = $("clip-axis");
    [...axis.options].filter((o) => o.value === "custom").forEach((o) => o.remove());
    let value = "";
    if (planes.length === 1) {
        const p = planes[0];
        const a = [0, 1, 2].find((i) => p[3 + i] !== 0 && p[3 + (i + 1) % 3] === 0 &&
                                        p[3 + (i + 2) % 3] === 0);
        if (a !== undefined) {
            value = String(a);
            const [lo, hi] = meshBounds();
            if (document.activeElement !== $("clip-pos") && hi[a] > lo[a])
                $("clip-pos").value = String((p[a] - lo[a]) / (hi[a] - lo[a]));
            $("clip-flip").checked = p[3 + a] < 0;
        }
    }
    if (planes.length > 0 && value === "") {
        axis.add(new Option(`custom (${planes.length})`, "custom"));
        value = "custom";
    }
    axis.value = value;
    $("clip-pos").disabled = $("clip-flip").disabled = value === "" || value === "custom";
    $("clip-surface").disabled = planes.length === 0;
}

/// The axis (0, 1, 2) of the state's one clip plane across an axis, or -1.
function clipAxis() {
    const planes = (session.state && session.state.clip_planes) || [];
    if (planes.length !== 1) return -1;
    const n = planes[0].slice(3);
    return [0, 1, 2].find((a) => n[a] !== 0 && n[(a + 1) % 3] === 0 && n[(a + 2) % 3] === 0) ?? -1;
}

let clipFrame = 0;

/// Moves the clip plane along its axis by a pointer motion of (dx, dy) pixels in the view (kept
/// within the mesh's bounds); one interactive frame per animation frame.
function moveClipPlane(dx, dy, height) {
    const a = clipAxis();
    if (a < 0) return;
    const plane = [...session.state.clip_planes[0]];
    const axis = [0, 0, 0];
    axis[a] = 1;
    const [lo, hi] = meshBounds();
    const t = cam.dragAlong(session.state.camera, axis, dx, dy, height);
    plane[a] = Math.min(hi[a], Math.max(lo[a], plane[a] + t));
    session.state.clip_planes = [plane];
    fillClip(session.state.clip_planes);
    if (!clipFrame) {
        clipFrame = requestAnimationFrame(() => {
            clipFrame = 0;
            if (drag && drag.mode === "clip") sendSet({clip_planes: session.state.clip_planes}, true);
        });
    }
}

$("clip-axis").addEventListener("change", () => {
    if ($("clip-axis").value !== "custom") sendSet({clip_planes: clipPlanesFromControls()});
});
$("clip-pos").addEventListener("input", () =>
    sendSet({clip_planes: clipPlanesFromControls()}, true));
$("clip-pos").addEventListener("change", () => sendSet({clip_planes: clipPlanesFromControls()}));
$("clip-flip").addEventListener("change", () => sendSet({clip_planes: clipPlanesFromControls()}));
$("clip-surface").addEventListener("change", (e) => sendSet({clip_surface: e.target.checked}));

// ---- Isosurfaces: a row each (value, opacity, colour by the map or its own, remove); the
// transfer-function editor shows them as markers

/// Sends the state's isosurfaces with entry i changed by `change` ({value, opacity, color}).
function setIso(i, change, interactive = false) {
    const list = [...(session.state.iso || [])];
    list[i] = isoText({...parseIso(list[i]), ...change});
    sendSet({iso: list}, interactive);
}

function isoRow(text, i) {
    const iso = parseIso(text);
    const row = document.createElement("div");
    row.className = "iso-row";
    row.dataset.index = String(i);
    const value = Object.assign(document.createElement("input"),
                                {type: "number", step: "any", title: "Value"});
    value.className = "iso-value";
    value.value = fmt(iso.value, 7);
    value.addEventListener("change", () => {
        const v = Number(value.value);
        if (value.value.trim() === "" || !Number.isFinite(v)) {
            showError("isosurface value: a finite number");
            updateControls();
            return;
        }
        setIso(i, {value: v});
    });
    const opacity = Object.assign(document.createElement("input"),
                                  {type: "range", min: "0.05", max: "1", step: "0.05",
                                   title: "Opacity (1: opaque)"});
    opacity.className = "iso-opacity";
    opacity.value = String(iso.opacity);
    opacity.addEventListener("input", () => setIso(i, {opacity: Number(opacity.value)}, true));
    opacity.addEventListener("change", () => setIso(i, {opacity: Number(opacity.value)}));
    const mapped = Object.assign(document.createElement("input"),
                                 {type: "checkbox", title: "Colour by the colour map"});
    mapped.className = "iso-mapped";
    mapped.checked = !iso.color;
    const color = Object.assign(document.createElement("input"),
                                {type: "color", title: "The surface's own colour"});
    color.className = "iso-color";
    color.value = iso.color || "#ffffff";
    color.disabled = !iso.color;
    mapped.addEventListener("change", () =>
        setIso(i, {color: mapped.checked ? null : color.value}));
    color.addEventListener("change", () => setIso(i, {color: color.value}));
    const remove = Object.assign(document.createElement("button"),
                                 {type: "button", textContent: "×", title: "Remove"});
    remove.className = "iso-remove";
    remove.addEventListener("click", () =>
        sendSet({iso: (session.state.iso || []).filter((_, j) => j !== i)}));
    row.append(value, opacity, mapped, color, remove);
    return row;
}

/// Shows the state's isosurfaces (the rows are rebuilt unless a value being typed or an opacity
/// being dragged has the focus).
function fillIso(list) {
    const box = $("iso-list");
    const max = (session.info && session.info.limits && session.info.limits.max_iso) || 8;
    $("iso-add").disabled = list.length >= max;
    tfEditor.maxIsos = max;
    const a = document.activeElement;
    const editing = box.contains(a) && (a.type === "number" || a.type === "range");
    if (box.dataset.shown === JSON.stringify(list) || editing) return;
    box.dataset.shown = JSON.stringify(list);
    box.replaceChildren(...list.map(isoRow));
}

$("iso-add").addEventListener("click", () => {
    const [lo, hi] = session.state.range;
    const list = session.state.iso || [];
    sendSet({iso: [...list, isoText({value: 0.5 * (lo + hi), opacity: 1, color: null})]});
});

// ---- Time steps ------------------------------------------------------------------------------

/// Shows the time row for a file with several time steps: the slider at `step`, its time.
function fillTime(step) {
    const times = (session.info && session.info.times) || [0];
    $("time-row").hidden = times.length < 2;
    const slider = $("time");
    slider.max = String(times.length - 1);
    if (document.activeElement !== slider) slider.value = String(step);
    // The label: the step of the frame shown (the slider: the one asked for).
    const shown = Math.min(session.shownStep ?? step, times.length - 1);
    $("time-value").textContent = `${fmt(times[shown], 6)} (${shown + 1}/${times.length})`;
}

let playTimer = null;  // while playing: the interval that steps on

function stopPlaying() {
    if (playTimer !== null) clearInterval(playTimer);
    playTimer = null;
    $("time-play").textContent = "▶";
    $("time-play").title = "Play the time steps";
}

$("time").addEventListener("input", (e) => {
    stopPlaying();
    sendSet({step: Number(e.target.value)}, true);
});
$("time").addEventListener("change", (e) => sendSet({step: Number(e.target.value)}));
$("time-play").addEventListener("click", () => {
    if (playTimer !== null) return stopPlaying();
    // Two bars (not U+23F8, which Debian's Chromium fonts lack: it showed as an empty box).
    $("time-play").textContent = "❚❚";
    $("time-play").title = "Pause";
    // One step every 250 ms, the newest wins: a slow frame drops steps rather than queueing.
    playTimer = setInterval(() => {
        const count = ((session.info && session.info.times) || [0]).length;
        const next = ((session.state && session.state.step) || 0) + 1;
        sendSet({step: next % count}, false);
    }, 250);
});

$("size").addEventListener("change", (e) => {
    fitView = e.target.value === "fit";
    if (fitView) {
        $("size-custom").hidden = true;
        fitSize();
        return;
    }
    if (e.target.value === "custom") {
        $("size-custom").hidden = false;
        $("size-w").value = session.state.size[0];
        $("size-h").value = session.state.size[1];
        $("size-w").focus();
        return;
    }
    $("size-custom").hidden = true;
    applySize(e.target.value.split("x").map(Number));
});
$("size-apply").addEventListener("click", () => {
    applySize([Number($("size-w").value), Number($("size-h").value)]);
});
for (const id of ["size-w", "size-h"]) {
    $(id).addEventListener("keydown", (e) => {
        if (e.key === "Enter") $("size-apply").click();
    });
}

// Fit the view: the image is rendered at the size its area has on the screen (device pixels),
// re-sent when the area changes; the default unless `uvr view --size` was given (info's
// fit_size). On a CPU the pixels are most of a frame's time.
let fitView = false;
let fitTimer = 0;
const kFitSettleMs = 250;

function fitSize() {
    if (!fitView || !session.state) return;
    const wrap = $("view-wrap");
    const style = getComputedStyle(wrap);
    const px = (v) => parseFloat(v) || 0;
    const dpr = window.devicePixelRatio || 1;
    const limits = (session.info && session.info.limits) || {};
    const lo = limits.min_size || 16, hi = limits.max_size || 4096;
    const side = (v) => Math.max(lo, Math.min(hi, Math.floor(v * dpr)));
    const w = side(wrap.clientWidth - px(style.paddingLeft) - px(style.paddingRight));
    const h = side(wrap.clientHeight - px(style.paddingTop) - px(style.paddingBottom));
    const [sw, sh] = session.state.size;
    if (Math.abs(w - sw) > 2 || Math.abs(h - sh) > 2) sendSet({size: [w, h]});
}

new ResizeObserver(() => {
    clearTimeout(fitTimer);
    fitTimer = setTimeout(fitSize, kFitSettleMs);
}).observe($("view-wrap"));

function applySize([w, h]) {
    const limits = (session.info && session.info.limits) || {};
    const lo = limits.min_size || 16, hi = limits.max_size || 4096;
    if (![w, h].every((v) => Number.isInteger(v) && v >= lo && v <= hi)) {
        showError(`image size: each side must be a whole number in [${lo}, ${hi}]`);
        return;
    }
    $("size-custom").hidden = true;
    sendSet({size: [w, h]});
}

$("preset").addEventListener("change", (e) => {
    // The server answers with `state` holding the preset's colours (the opacity stays).
    sendSet({preset: e.target.value});
});
$("log-scale").addEventListener("change", (e) => {
    sendSet({tf: {...session.state.tf, log: e.target.checked}});
});

/// The value a range input stands for: the state's exact value while the input still shows its
/// rounded text, else what was typed.
function rangeInputValue(id, index) {
    const input = $(id);
    return input.value === input.dataset.shown ? session.state.range[index] : Number(input.value);
}

function applyRange() {
    const lo = rangeInputValue("range-lo", 0), hi = rangeInputValue("range-hi", 1);
    if (!Number.isFinite(lo) || !Number.isFinite(hi) || !(lo < hi)) {
        showError("range: lo must be below hi");
        updateControls();
        return;
    }
    sendSet({range: [lo, hi]});
}
for (const id of ["range-lo", "range-hi"]) {
    $(id).addEventListener("change", applyRange);
    $(id).addEventListener("keydown", (e) => {
        if (e.key === "Enter") e.target.blur();
    });
}
$("range-reset").addEventListener("click", () => {
    // The histogram spans the current field's finite range; before one arrives, info's field.
    const h = session.histogram;
    let range = h && h.range;
    if (!range) {
        const entry = matchField(fieldList, session.state.field);
        range = entry && entry.field.range;
    }
    if (range) sendSet({range: [...range]});
});

// Colour maps from a file: the picker, or dropped on the editor.
$("cmap-file").addEventListener("change", (e) => {
    const file = e.target.files && e.target.files[0];
    if (file) readColorMap(file);
    e.target.value = "";  // the same file again fires `change` again
});
const drop = $("tf-drop");
for (const type of ["dragenter", "dragover"]) {
    drop.addEventListener(type, (e) => {
        if (![...e.dataTransfer.types].includes("Files")) return;
        e.preventDefault();
        e.dataTransfer.dropEffect = "copy";
        drop.classList.add("over");
    });
}
drop.addEventListener("dragleave", () => drop.classList.remove("over"));
drop.addEventListener("drop", (e) => {
    e.preventDefault();
    drop.classList.remove("over");
    const file = e.dataTransfer.files && e.dataTransfer.files[0];
    if (file) readColorMap(file);
});

let colormapText = null;   // the file whose maps #cmap-name lists

function readColorMap(file) {
    const reader = new FileReader();
    reader.onload = () => {
        colormapText = String(reader.result);
        // A presets file holds many maps: offer their names and send the first; the server
        // parses the text either way (and reports what is wrong with it).
        const names = colorMapNames(colormapText);
        const select = $("cmap-name");
        select.hidden = names.length < 2;
        select.replaceChildren(...names.map((n) => new Option(n, n)));
        sendSet(names.length > 1 ? {colormap_json: colormapText, colormap_name: names[0]}
                                 : {colormap_json: colormapText});
    };
    reader.onerror = () => showError(`could not read ${file.name}`);
    reader.readAsText(file);
}
$("cmap-name").addEventListener("change", (e) => {
    if (colormapText) sendSet({colormap_json: colormapText, colormap_name: e.target.value});
});

/// Names of the colour maps in a ParaView colour-map JSON text (none when it is not JSON).
function colorMapNames(text) {
    try {
        const j = JSON.parse(text);
        const maps = Array.isArray(j) ? j : [j];
        return maps.filter((m) => m && m.RGBPoints && m.Name).map((m) => String(m.Name));
    } catch {
        return [];
    }
}

// ---- Snapshot and exports --------------------------------------------------------------------

function download(blob, name) {
    const url = URL.createObjectURL(blob);
    const a = document.createElement("a");
    a.href = url;
    a.download = name;
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(url), 10000);
}

/// Asks for an `export` and calls `then` with it (exports are answered in order, by `export`
/// or by an `error` for the request). A `quiet` request (the background refresh of the command
/// field) shows its error in the field instead of on the error line.
function requestExport(then, quiet = false) {
    if (send({type: "export"})) session.exportWaiters.push({then, quiet});
}

function onExport(m) {
    session.lastExport = m;
    session.exportFresh = true;
    $("command").value = m.command || "";
    const waiter = session.exportWaiters.shift();
    if (waiter) waiter.then(m);
}

// The command field follows the state: a fresh export a moment after each final change.
let exportTimer = 0;
function scheduleExportRefresh() {
    clearTimeout(exportTimer);
    exportTimer = setTimeout(() => requestExport(() => {}, true), kExportRefreshMs);
}

$("save-png").addEventListener("click", () => send({type: "snapshot"}));
$("export-tf").addEventListener("click", () => requestExport((m) => {
    download(new Blob([m.tf_json], {type: "application/json"}), m.tf_file || "uvr-tf.json");
}));
$("export-camera").addEventListener("click", () => requestExport((m) => {
    download(new Blob([m.pvcc], {type: "application/xml"}), m.camera_file || "uvr-camera.pvcc");
}));
$("copy-command").addEventListener("click", () => {
    // Copy at once when the field is current (inside the click, where browsers allow it);
    // otherwise after a fresh export.
    if (session.exportFresh && session.lastExport) copyCommand(session.lastExport.command);
    else requestExport((m) => copyCommand(m.command));
});

async function copyCommand(text) {
    const note = $("copy-note");
    try {
        await navigator.clipboard.writeText(text);
        note.textContent = "Copied to the clipboard.";
        return;
    } catch {
        // No clipboard API (plain http to a host that is not localhost) or no permission.
    }
    const field = $("command");
    field.focus();
    field.select();
    let copied = false;
    try {
        copied = document.execCommand("copy");
    } catch {
        copied = false;
    }
    note.textContent = copied ? "Copied to the clipboard."
                              : "The browser refused the clipboard: the command is selected above.";
}

// ---- Status ----------------------------------------------------------------------------------

function updateFrameStats(header) {
    const s = header.stats || {};
    const num = (v, d = 1) => (Number.isFinite(v) ? v.toFixed(d) : "–");
    // The library's frame report (docs/STATS.md): seconds, and counts over the whole frame.
    const pixels = s.image ? s.image.width * s.image.height : NaN;
    $("stat-render-ms").textContent = `${num(s.render_seconds * 1e3)} ms`;
    $("stat-spp").textContent = num(s.mean_samples_per_pixel);
    $("stat-partitions").textContent =
        `${num(s.partitions_visited / pixels)} visited / ` +
        `${num(s.partitions_skipped / pixels)} skipped`;
    $("stat-frame").textContent =
        `${header.full ? "full" : "reduced"} ${header.width}×${header.height} ${header.format}`;
    const device = s.device || (session.info && session.info.device) || "–";
    // Under "auto" the frame says which method it picked (and why, on hover).
    const picked = $("method").value === "auto" && s.method ? `auto → ${s.method}` : s.method;
    $("stat-device").textContent = picked ? `${device} · ${picked}` : device;
    $("stat-device").title = s.method_reason || "";
}

// Frames per second: frames received over the last second, refreshed 4 times a second.
setInterval(() => {
    const now = performance.now();
    const times = session.frameTimes;
    while (times.length && now - times[0] > 1000) times.shift();
    $("stat-fps").textContent = String(times.length);
}, 250);

function fillMeshInfo(m) {
    const n = (v) => (Number.isFinite(v) ? v.toLocaleString("en-US") : "–");
    $("mesh-file").textContent = m.file || "–";
    $("mesh-cells").textContent = n(m.cells);
    $("mesh-tets").textContent = m.rendered_cells || (m.tetrahedra == null ? "–" : n(m.tetrahedra) + " tetrahedra");
    $("mesh-types").textContent = m.cell_types
        ? Object.entries(m.cell_types).map(([k, v]) => `${k} ${n(v)}`).join(", ") : "–";
    const b = m.bounds;
    $("mesh-bounds").textContent = b
        ? ["x", "y", "z"].map((a, i) => `${a} [${fmt(b[0][i], 4)}, ${fmt(b[1][i], 4)}]`).join("  ")
        : "–";
    const sec = (v) => (Number.isFinite(v) ? `${v.toFixed(2)} s` : "–");
    $("stat-load").textContent = `${sec(m.load_seconds)} / ${sec(m.prepare_seconds)}`;
    $("stat-device").textContent = m.device || "–";
    $("notes").replaceChildren(...(m.notes || []).map((t) => {
        const li = document.createElement("li");
        li.textContent = t;
        return li;
    }));
}

let errorTimer = 0;
function showError(text) {
    const line = $("error-line");
    line.textContent = text;
    line.classList.add("visible");
    clearTimeout(errorTimer);
    errorTimer = setTimeout(() => line.classList.remove("visible"), kErrorShowMs);
}

function onServerError(m) {
    session.errorCount++;
    session.lastError = {message: m.message, request: m.request ?? null};
    if (m.request === "export") {
        const waiter = session.exportWaiters.shift();
        if (waiter && waiter.quiet) {
            session.lastExport = null;
            $("command").value = `(no command: ${m.message})`;
            return;
        }
    }
    showError(m.request ? `${m.request}: ${m.message}` : m.message);
    hideProgress();
}

let progressTimer = 0;
function onProgress(m) {
    const box = $("progress"), bar = $("progress-bar");
    box.hidden = false;
    const f = m.fraction;
    const known = typeof f === "number" && Number.isFinite(f);
    bar.classList.toggle("indeterminate", !known);
    bar.style.width = known ? `${Math.round(100 * Math.min(1, Math.max(0, f)))}%` : "";
    $("progress-label").textContent = m.phase + (known ? ` ${Math.round(100 * f)}%` : "…");
    // A phase that ends without a later message hides itself.
    clearTimeout(progressTimer);
    progressTimer = setTimeout(hideProgress, known && f >= 1 ? 500 : 60000);
}
function hideProgress() {
    clearTimeout(progressTimer);
    $("progress").hidden = true;
}
function hideProgressIfDone() {
    // A full frame means the preparation behind any progress message is over.
    if (session.lastFrame && session.lastFrame.full) hideProgress();
}

function showBanner(text) {
    $("banner-text").textContent = text;
    $("banner").hidden = false;
}
$("banner-reload").addEventListener("click", () => location.reload());

// ---- Test hook -------------------------------------------------------------------------------

/// Read-only view of the session for tests (tests/web/view_page_test.py), which wait on it
/// instead of sleeping; `set` changes the state as the controls do, `sendRaw` puts any text on
/// the socket, as a misbehaving client would.
window.uvrView = Object.freeze({
    get connected() { return session.connected; },
    get info() { return structuredClone(session.info); },
    get state() { return structuredClone(session.state); },
    get histogram() { return structuredClone(session.histogram); },
    get lastFrame() { return session.lastFrame ? {...session.lastFrame} : null; },
    get frameCount() { return session.frameCount; },
    get framesDecoded() { return session.framesDecoded; },
    get lastSeq() { return session.seq; },
    get lastError() { return session.lastError ? {...session.lastError} : null; },
    get errorCount() { return session.errorCount; },
    get messageCounts() { return {...session.counts}; },
    get lastExport() { return session.lastExport ? {...session.lastExport} : null; },
    get lastPong() { return session.lastPong ? {...session.lastPong} : null; },
    /// Sends a `set` as the controls do (the local state follows); returns its seq.
    set(changes, interactive = false) { return sendSet(structuredClone(changes), interactive); },
    sendRaw(text) {
        if (!session.ws || session.ws.readyState !== WebSocket.OPEN) return false;
        session.ws.send(text);
        return true;
    },
    opacityPointClient(i) { return tfEditor.pointClient(i); },
    isoHandleClient(i) { return tfEditor.isoClient(i); },
});

connect();
