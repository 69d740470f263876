// SPDX-License-Identifier: MIT
// The transfer-function editor's canvas: the field's histogram (log-scaled counts) over the
// transfer function's value range, the opacity curve over it with its control points (drag to
// move, double-click empty space to add, double-click or right-click a point to remove; at least
// two stay), the colour map beneath the curve and as a bar at the bottom. Isosurfaces show as
// vertical markers: Shift+click adds one at the value under the pointer, dragging a marker's
// handle (the triangle at the top) moves it, right-click on the handle removes it.

import {colorAt, css, opacityAt} from "./colormap.js";

const kPointRadius = 5;    // drawn radius of a control point, CSS pixels
const kHitRadius = 9;      // how near a pointer must be to grab a point
const kBarHeight = 16;     // colour bar
const kPad = 8;            // left/right margin, so the end points can be grabbed
const kTop = 8;
const kGap = 6;            // between the plot and the colour bar
const kMinSeparation = 1e-4;  // smallest x gap kept between neighbouring points

/// Value at normalised transfer-function position t over range [lo, hi] (log10-spaced when
/// `log`; a range from 0 or below then starts at min(hi / 10^4, 1), as ParaView does).
export function valueAt(t, lo, hi, log) {
    if (!log) return lo + t * (hi - lo);
    const l0 = lo > 0 ? lo : Math.min(hi / 1e4, 1);
    if (!(hi > l0)) return lo + t * (hi - lo);
    return Math.pow(10, Math.log10(l0) + t * (Math.log10(hi) - Math.log10(l0)));
}

/// Normalised transfer-function position of `value` over [lo, hi] (valueAt's inverse).
export function positionOf(value, lo, hi, log) {
    if (log) {
        const l0 = lo > 0 ? lo : Math.min(hi / 1e4, 1);
        if (hi > l0 && value > 0)
            return (Math.log10(value) - Math.log10(l0)) / (Math.log10(hi) - Math.log10(l0));
        if (hi > l0) return -Infinity;
    }
    return hi > lo ? (value - lo) / (hi - lo) : 0.5;
}

/// An isosurface as the state writes it ("VALUE[,OPACITY[,#RRGGBB]]", as `--iso` takes it)
/// split into {value, opacity, color} (color: "#rrggbb", or null for the colour map's).
export function parseIso(text) {
    const [v, o, c] = String(text).split(",");
    return {value: Number(v), opacity: o === undefined ? 1 : Number(o), color: c || null};
}

/// The state's text of an isosurface {value, opacity, color}.
export function isoText({value, opacity, color}) {
    const num = (x) => String(Number(Number(x).toPrecision(7)));
    let out = num(value);
    if (opacity !== 1 || color) out += `,${num(opacity)}`;
    if (color) out += `,${color}`;
    return out;
}

export class TfEditor {
    /// `onOpacity(points, interactive)` is called with a new copy of the opacity points on every
    /// edit: interactive true while a point is dragged, false for a final value. `onIso(texts,
    /// interactive)` likewise with the isosurfaces' new list when one is added, moved or removed.
    constructor(canvas, onOpacity, onIso = () => {}) {
        this.canvas = canvas;
        this.onOpacity = onOpacity;
        this.onIso = onIso;
        this.tf = null;
        this.range = [0, 1];
        this.histogram = null;
        this.isos = [];         // the state's isosurfaces, as texts
        this.maxIsos = 8;       // info.limits.max_iso once it comes
        this.drag = null;       // {index, points, moved} or {iso, isos, moved}
        this.hover = -1;
        this.pendingFrame = 0;  // requestAnimationFrame id of a pending interactive send
        canvas.addEventListener("pointerdown", (e) => this.pointerDown(e));
        canvas.addEventListener("pointermove", (e) => this.pointerMove(e));
        canvas.addEventListener("pointerup", (e) => this.pointerUp(e));
        canvas.addEventListener("pointercancel", (e) => this.pointerUp(e));
        canvas.addEventListener("dblclick", (e) => this.doubleClick(e));
        canvas.addEventListener("contextmenu", (e) => this.contextMenu(e));
        new ResizeObserver(() => this.draw()).observe(canvas);
    }

    /// Shows a new transfer function, value range, histogram and isosurfaces (any may be
    /// undefined: kept).
    update({tf, range, histogram, isos} = {}) {
        if (tf !== undefined) this.tf = tf;
        if (range !== undefined) this.range = range;
        if (histogram !== undefined) this.histogram = histogram;
        if (isos !== undefined && !(this.drag && this.drag.isos)) this.isos = isos;
        // A point being dragged keeps following the pointer, whatever the server said last.
        this.draw();
    }

    points() {
        return this.drag && this.drag.points ? this.drag.points : (this.tf ? this.tf.opacity : []);
    }

    isoList() {
        return this.drag && this.drag.isos ? this.drag.isos : this.isos;
    }

    /// Client x (CSS pixels in the canvas) of isosurface value v, or null off the axis.
    isoX(v) {
        const t = positionOf(v, this.range[0], this.range[1], this.tf && this.tf.log);
        if (!(t >= 0 && t <= 1)) return null;
        const p = this.plot();
        return p.x0 + t * (p.x1 - p.x0);
    }

    /// Index of the isosurface whose handle (a triangle at the plot's top) is under the event.
    hitIso(e) {
        const {cx, cy} = this.fromEvent(e);
        const p = this.plot();
        if (cy > p.y0 + 2 * kHitRadius) return -1;
        let best = -1, bestD = kHitRadius;
        this.isoList().forEach((text, i) => {
            const x = this.isoX(parseIso(text).value);
            if (x !== null && Math.abs(x - cx) <= bestD) {
                best = i;
                bestD = Math.abs(x - cx);
            }
        });
        return best;
    }

    /// Client (viewport) coordinates of isosurface i's handle: for tests that drag it.
    isoClient(i) {
        const list = this.isoList();
        if (i < 0 || i >= list.length) return null;
        const x = this.isoX(parseIso(list[i]).value);
        if (x === null) return null;
        const r = this.canvas.getBoundingClientRect();
        return {x: r.left + x, y: r.top + this.plot().y0 + 4};
    }

    // The plot's rectangle in CSS pixels.
    plot() {
        const w = this.canvas.clientWidth, h = this.canvas.clientHeight;
        return {x0: kPad, x1: w - kPad, y0: kTop, y1: h - kBarHeight - kGap - 2, w, h};
    }

    toClient([x, alpha]) {
        const p = this.plot();
        return {x: p.x0 + x * (p.x1 - p.x0), y: p.y1 - alpha * (p.y1 - p.y0)};
    }

    fromEvent(e) {
        const r = this.canvas.getBoundingClientRect();
        const p = this.plot();
        const cx = e.clientX - r.left, cy = e.clientY - r.top;
        return {cx, cy,
                x: Math.min(1, Math.max(0, (cx - p.x0) / (p.x1 - p.x0))),
                alpha: Math.min(1, Math.max(0, (p.y1 - cy) / (p.y1 - p.y0)))};
    }

    /// Index of the control point within kHitRadius of the event, or -1.
    hit(e) {
        const {cx, cy} = this.fromEvent(e);
        let best = -1, bestD = kHitRadius;
        this.points().forEach((pt, i) => {
            const c = this.toClient(pt);
            const d = Math.hypot(c.x - cx, c.y - cy);
            if (d <= bestD) {
                best = i;
                bestD = d;
            }
        });
        return best;
    }

    /// Client (viewport) coordinates of opacity point i: for tests that drag it.
    pointClient(i) {
        const pts = this.points();
        if (i < 0 || i >= pts.length) return null;
        const r = this.canvas.getBoundingClientRect();
        const c = this.toClient(pts[i]);
        return {x: r.left + c.x, y: r.top + c.y};
    }

    pointerDown(e) {
        if (e.button !== 0 || !this.tf) return;
        if (e.shiftKey) {
            // A new isosurface at the value under the pointer.
            e.preventDefault();
            const {x} = this.fromEvent(e);
            const [lo, hi] = this.range;
            const value = valueAt(x, lo, hi, this.tf.log);
            if (this.isos.length >= this.maxIsos || !Number.isFinite(value)) return;
            this.isos = [...this.isos, isoText({value, opacity: 1, color: null})];
            this.onIso([...this.isos], false);
            this.draw();
            return;
        }
        const k = this.hitIso(e);
        if (k >= 0 && this.hit(e) < 0) {
            e.preventDefault();
            this.canvas.setPointerCapture(e.pointerId);
            this.drag = {iso: k, isos: [...this.isos], moved: false};
            this.draw();
            return;
        }
        const i = this.hit(e);
        if (i < 0) return;
        e.preventDefault();
        this.canvas.setPointerCapture(e.pointerId);
        this.drag = {index: i, points: this.tf.opacity.map((p) => [...p]), moved: false};
        this.draw();
    }

    pointerMove(e) {
        if (!this.drag) {
            const h = this.tf ? this.hit(e) : -1;
            const onIso = this.tf && h < 0 && this.hitIso(e) >= 0;
            this.canvas.style.cursor = h >= 0 ? "grab" : onIso ? "ew-resize" : "crosshair";
            if (h !== this.hover) {
                this.hover = h;
                this.draw();
            }
            return;
        }
        if (this.drag.isos) {
            const {x} = this.fromEvent(e);
            const iso = parseIso(this.drag.isos[this.drag.iso]);
            iso.value = valueAt(x, this.range[0], this.range[1], this.tf.log);
            this.drag.isos[this.drag.iso] = isoText(iso);
            this.drag.moved = true;
            this.draw();
            if (!this.pendingFrame) {
                this.pendingFrame = requestAnimationFrame(() => {
                    this.pendingFrame = 0;
                    if (this.drag && this.drag.isos) this.onIso([...this.drag.isos], true);
                });
            }
            return;
        }
        const {x, alpha} = this.fromEvent(e);
        const pts = this.drag.points, i = this.drag.index;
        // Keep x strictly between the neighbours so the points stay sorted.
        const lo = i > 0 ? pts[i - 1][0] + kMinSeparation : 0;
        const hi = i + 1 < pts.length ? pts[i + 1][0] - kMinSeparation : 1;
        pts[i] = [Math.min(hi, Math.max(lo, x)), alpha];
        this.drag.moved = true;
        this.draw();
        // At most one interactive message per animation frame.
        if (!this.pendingFrame) {
            this.pendingFrame = requestAnimationFrame(() => {
                this.pendingFrame = 0;
                if (this.drag) this.onOpacity(this.drag.points.map((p) => [...p]), true);
            });
        }
    }

    pointerUp(e) {
        if (!this.drag) return;
        if (this.canvas.hasPointerCapture(e.pointerId)) {
            this.canvas.releasePointerCapture(e.pointerId);
        }
        if (this.pendingFrame) cancelAnimationFrame(this.pendingFrame);
        this.pendingFrame = 0;
        const {points, isos, moved} = this.drag;
        this.drag = null;
        if (isos) {
            if (moved) {
                this.isos = isos;
                this.onIso([...isos], false);
            }
        } else if (moved) {
            this.tf = {...this.tf, opacity: points};
            this.onOpacity(points.map((p) => [...p]), false);
        }
        this.draw();
    }

    removePoint(i) {
        const pts = this.tf.opacity;
        if (pts.length <= 2) return;
        const next = pts.filter((_, j) => j !== i).map((p) => [...p]);
        this.tf = {...this.tf, opacity: next};
        this.hover = -1;
        this.onOpacity(next, false);
        this.draw();
    }

    doubleClick(e) {
        if (!this.tf) return;
        e.preventDefault();
        const i = this.hit(e);
        if (i >= 0) {
            this.removePoint(i);
            return;
        }
        const {x, alpha} = this.fromEvent(e);
        const pts = this.tf.opacity.map((p) => [...p]);
        if (pts.some((p) => Math.abs(p[0] - x) < kMinSeparation)) return;
        pts.push([x, alpha]);
        pts.sort((a, b) => a[0] - b[0]);
        this.tf = {...this.tf, opacity: pts};
        this.onOpacity(pts.map((p) => [...p]), false);
        this.draw();
    }

    contextMenu(e) {
        e.preventDefault();
        if (!this.tf) return;
        const i = this.hit(e);
        if (i >= 0) {
            this.removePoint(i);
            return;
        }
        const k = this.hitIso(e);
        if (k >= 0) {
            this.isos = this.isos.filter((_, j) => j !== k);
            this.onIso([...this.isos], false);
            this.draw();
        }
    }

    /// Histogram count at normalised position t of the transfer function's axis (the histogram's
    /// own bins are linear over its range, which may differ from the transfer function's).
    countAt(t) {
        const h = this.histogram;
        if (!h || !h.counts || h.counts.length === 0) return 0;
        const [lo, hi] = this.range;
        const v = valueAt(t, lo, hi, this.tf && this.tf.log);
        const [h0, h1] = h.range;
        if (!(h1 > h0) || v < h0 || v > h1) return 0;
        const n = h.counts.length;
        return h.counts[Math.min(n - 1, Math.floor(((v - h0) / (h1 - h0)) * n))];
    }

    draw() {
        const c = this.canvas;
        const dpr = window.devicePixelRatio || 1;
        const w = c.clientWidth, h = c.clientHeight;
        if (w === 0 || h === 0) return;
        if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
            c.width = Math.round(w * dpr);
            c.height = Math.round(h * dpr);
        }
        const g = c.getContext("2d");
        g.setTransform(dpr, 0, 0, dpr, 0, 0);
        g.clearRect(0, 0, w, h);
        g.fillStyle = "#101318";
        g.fillRect(0, 0, w, h);
        if (!this.tf) return;
        const p = this.plot();
        const pw = p.x1 - p.x0, ph = p.y1 - p.y0;
        const columns = Math.max(2, Math.round(pw));
        const tAt = (i) => i / (columns - 1);
        const colors = [];
        for (let i = 0; i < columns; i++) {
            colors.push(colorAt(this.tf.colors, this.tf.color_space, tAt(i)));
        }

        // Histogram: log(1 + count) scaled to the largest bin.
        const counts = [];
        for (let i = 0; i < columns; i++) counts.push(this.countAt(tAt(i)));
        const top = Math.log1p(Math.max(1, ...counts));
        g.fillStyle = "rgba(200, 210, 225, 0.20)";
        for (let i = 0; i < columns; i++) {
            const bh = (Math.log1p(counts[i]) / top) * ph;
            if (bh > 0) g.fillRect(p.x0 + (i / columns) * pw, p.y1 - bh, pw / columns + 0.5, bh);
        }

        // The colour map under the opacity curve.
        const pts = this.points();
        for (let i = 0; i < columns; i++) {
            const a = opacityAt(pts, tAt(i));
            if (a <= 0) continue;
            g.fillStyle = css(colors[i], 0.55);
            g.fillRect(p.x0 + (i / columns) * pw, p.y1 - a * ph, pw / columns + 0.5, a * ph);
        }

        // Frame of the plot and the curve, flat beyond the end points.
        g.strokeStyle = "rgba(255,255,255,0.12)";
        g.lineWidth = 1;
        g.strokeRect(p.x0 - 0.5, p.y0 - 0.5, pw + 1, ph + 1);
        g.strokeStyle = "#e8ecf2";
        g.lineWidth = 1.5;
        g.beginPath();
        g.moveTo(p.x0, this.toClient([0, pts[0][1]]).y);
        for (const pt of pts) {
            const q = this.toClient(pt);
            g.lineTo(q.x, q.y);
        }
        g.lineTo(p.x1, this.toClient([1, pts[pts.length - 1][1]]).y);
        g.stroke();
        pts.forEach((pt, i) => {
            const q = this.toClient(pt);
            const active = (this.drag && this.drag.index === i) || (!this.drag && this.hover === i);
            g.beginPath();
            g.arc(q.x, q.y, active ? kPointRadius + 1.5 : kPointRadius, 0, 2 * Math.PI);
            g.fillStyle = css(colorAt(this.tf.colors, this.tf.color_space, pt[0]));
            g.fill();
            g.lineWidth = active ? 2 : 1.5;
            g.strokeStyle = active ? "#ffd166" : "#ffffff";
            g.stroke();
        });

        // Isosurfaces: a line across the plot in the surface's colour, a handle at the top.
        for (const text of this.isoList()) {
            const iso = parseIso(text);
            const x = this.isoX(iso.value);
            if (x === null) continue;
            const t = (x - p.x0) / pw;
            const color = iso.color || css(colorAt(this.tf.colors, this.tf.color_space, t));
            g.strokeStyle = color;
            g.globalAlpha = 0.35 + 0.65 * iso.opacity;
            g.lineWidth = 2;
            g.setLineDash([4, 3]);
            g.beginPath();
            g.moveTo(x, p.y0);
            g.lineTo(x, p.y1);
            g.stroke();
            g.setLineDash([]);
            g.globalAlpha = 1;
            g.beginPath();
            g.moveTo(x - 6, p.y0);
            g.lineTo(x + 6, p.y0);
            g.lineTo(x, p.y0 + 9);
            g.closePath();
            g.fillStyle = color;
            g.fill();
            g.lineWidth = 1;
            g.strokeStyle = "#ffffff";
            g.stroke();
        }

        // Colour bar.
        const by = h - kBarHeight - 2;
        for (let i = 0; i < columns; i++) {
            g.fillStyle = css(colors[i]);
            g.fillRect(p.x0 + (i / columns) * pw, by, pw / columns + 0.5, kBarHeight);
        }
        g.strokeStyle = "rgba(255,255,255,0.25)";
        g.lineWidth = 1;
        g.strokeRect(p.x0 - 0.5, by - 0.5, pw + 1, kBarHeight + 1);
    }
}
