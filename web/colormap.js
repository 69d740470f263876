// SPDX-License-Identifier: MIT
// Colour-map evaluation for the page's colour bar, the same interpolation the renderer uses
// (src/uvr/tf/transfer_function.cpp): RGB, CIE L*a*b* (D65, VTK's constants) and Moreland 2009's
// diverging Msh interpolation; HSV (hue linear from point to point, no wrap) for maps a server
// sends without resampling them. Colours are [r, g, b] in [0, 1]; maps are the protocol's
// `tf.colors` rows [x, r, g, b] with x increasing in [0, 1].

const clamp01 = (v) => Math.min(1, Math.max(0, v));

// sRGB <-> linear sRGB (IEC 61966-2-1 transfer curve).
const srgbToLinear = (c) => (c <= 0.04045 ? c / 12.92 : Math.pow((c + 0.055) / 1.055, 2.4));
const linearToSrgb = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * Math.pow(c, 1 / 2.4) - 0.055);

// D65 reference white, as VTK's vtkMath::XYZToLab uses it.
const kWhite = [0.9505, 1.0, 1.089];
const labF = (t) => (t > 0.008856 ? Math.cbrt(t) : 7.787 * t + 16 / 116);
function labFInverse(f) {
    const t = f * f * f;
    return t > 0.008856 ? t : (f - 16 / 116) / 7.787;
}

export function srgbToLab([r8, g8, b8]) {
    const r = srgbToLinear(r8), g = srgbToLinear(g8), b = srgbToLinear(b8);
    const x = 0.4124 * r + 0.3576 * g + 0.1805 * b;
    const y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
    const z = 0.0193 * r + 0.1192 * g + 0.9505 * b;
    const fx = labF(x / kWhite[0]), fy = labF(y / kWhite[1]), fz = labF(z / kWhite[2]);
    return [116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz)];
}

export function labToSrgb([l, a, bb]) {
    const fy = (l + 16) / 116, fx = fy + a / 500, fz = fy - bb / 200;
    const x = kWhite[0] * labFInverse(fx), y = kWhite[1] * labFInverse(fy),
          z = kWhite[2] * labFInverse(fz);
    const r = 3.2406 * x - 1.5372 * y - 0.4986 * z;
    const g = -0.9689 * x + 1.8758 * y + 0.0415 * z;
    const b = 0.0557 * x - 0.204 * y + 1.057 * z;
    return [r, g, b].map((c) => clamp01(linearToSrgb(c)));
}

// Moreland 2009, "Diverging Color Maps for Scientific Visualization", Sec. 4: the Msh polar form
// of L*a*b* (magnitude M, saturation s, hue h).
function labToMsh([l, a, b]) {
    const m = Math.hypot(l, a, b);
    return [m, m > 0 ? Math.acos(Math.min(1, Math.max(-1, l / m))) : 0, Math.atan2(b, a)];
}
const mshToLab = ([m, s, h]) => [m * Math.cos(s), m * Math.sin(s) * Math.cos(h),
                                 m * Math.sin(s) * Math.sin(h)];

// Moreland 2009, "AdjustHue": the hue to give an unsaturated colour of magnitude mUnsat so that
// the interpolation towards the saturated colour (mSat, sSat, hSat) spins the hue smoothly.
function adjustHue(mSat, sSat, hSat, mUnsat) {
    if (mSat >= mUnsat) return hSat;
    const spin = (sSat * Math.sqrt(mUnsat * mUnsat - mSat * mSat)) / (mSat * Math.sin(sSat));
    return hSat > -Math.PI / 3 ? hSat + spin : hSat - spin;
}

// Moreland 2009, "InterpolateColor": Msh interpolation, through an unsaturated white of magnitude
// max(M1, M2, 88) when both ends are saturated with hues more than pi/3 apart.
function interpolateDiverging(a, b, f) {
    const kUnsaturated = 0.05;
    let m1 = labToMsh(srgbToLab(a)), m2 = labToMsh(srgbToLab(b));
    if (m1[1] > kUnsaturated && m2[1] > kUnsaturated && Math.abs(m1[2] - m2[2]) > Math.PI / 3) {
        const mMid = Math.max(m1[0], m2[0], 88);
        if (f < 0.5) {
            m2 = [mMid, 0, 0];
            f = 2 * f;
        } else {
            m1 = [mMid, 0, 0];
            f = 2 * f - 1;
        }
    }
    if (m1[1] < kUnsaturated && m2[1] > kUnsaturated) {
        m1[2] = adjustHue(m2[0], m2[1], m2[2], m1[0]);
    } else if (m2[1] < kUnsaturated && m1[1] > kUnsaturated) {
        m2[2] = adjustHue(m1[0], m1[1], m1[2], m2[0]);
    }
    return labToSrgb(mshToLab(m1.map((v, i) => (1 - f) * v + f * m2[i])));
}

function rgbToHsv([r, g, b]) {
    const max = Math.max(r, g, b), min = Math.min(r, g, b), d = max - min;
    let h = 0;
    if (d > 0) {
        if (max === r) h = ((g - b) / d + 6) % 6;
        else if (max === g) h = (b - r) / d + 2;
        else h = (r - g) / d + 4;
    }
    return [h / 6, max > 0 ? d / max : 0, max];
}

function hsvToRgb([h, s, v]) {
    const k = (n) => (n + h * 6) % 6;
    const f = (n) => v - v * s * Math.max(0, Math.min(k(n), 4 - k(n), 1));
    return [f(5), f(3), f(1)];
}

/// The interpolation a protocol `color_space` names: "rgb", "lab", "diverging" or "hsv".
export function spaceKind(colorSpace) {
    const s = String(colorSpace || "RGB").toLowerCase();
    if (s.startsWith("lab") || s.startsWith("cielab")) return "lab";
    if (s === "diverging") return "diverging";
    if (s === "hsv") return "hsv";
    return "rgb";
}

/// Colour between a (f = 0) and b (f = 1) in the given space kind.
export function interpolate(kind, a, b, f) {
    switch (kind) {
        case "lab": {
            const la = srgbToLab(a), lb = srgbToLab(b);
            return labToSrgb(la.map((v, i) => v + f * (lb[i] - v)));
        }
        case "diverging":
            return interpolateDiverging(a, b, f);
        case "hsv": {
            const ha = rgbToHsv(a), hb = rgbToHsv(b);
            return hsvToRgb(ha.map((v, i) => v + f * (hb[i] - v)));
        }
        default:
            return a.map((v, i) => v + f * (b[i] - v));
    }
}

/// Colour of the map `colors` ([x, r, g, b] rows) at normalised position t (clamped).
export function colorAt(colors, colorSpace, t) {
    if (!colors || colors.length === 0) return [0, 0, 0];
    t = clamp01(Number.isNaN(t) ? 0 : t);
    if (t <= colors[0][0]) return colors[0].slice(1, 4);
    const last = colors[colors.length - 1];
    if (t >= last[0]) return last.slice(1, 4);
    let i = 0;
    while (i + 1 < colors.length && colors[i + 1][0] <= t) i++;
    const a = colors[i], b = colors[i + 1];
    const f = b[0] > a[0] ? (t - a[0]) / (b[0] - a[0]) : 0;
    return interpolate(spaceKind(colorSpace), a.slice(1, 4), b.slice(1, 4), f);
}

/// Opacity of the piecewise-linear `opacity` ([x, alpha] rows) at normalised position t.
export function opacityAt(points, t) {
    if (!points || points.length === 0) return 0;
    if (t <= points[0][0]) return points[0][1];
    const last = points[points.length - 1];
    if (t >= last[0]) return last[1];
    let i = 0;
    while (i + 1 < points.length && points[i + 1][0] <= t) i++;
    const a = points[i], b = points[i + 1];
    return b[0] > a[0] ? a[1] + ((t - a[0]) / (b[0] - a[0])) * (b[1] - a[1]) : a[1];
}

/// CSS rgb() text of an [r, g, b] colour in [0, 1].
export const css = (rgb, alpha = 1) =>
    `rgba(${rgb.map((c) => Math.round(255 * clamp01(c))).join(",")},${alpha})`;
