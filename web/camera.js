// SPDX-License-Identifier: MIT
// Camera math of the viewer's trackball, after VTK's vtkInteractorStyleTrackballCamera (the style
// ParaView's default "rotate / pan / zoom" mouse bindings follow). Cameras are the protocol's
// objects ({position, focal_point, view_up, view_angle, parallel, parallel_scale}, file
// coordinates, degrees); every function returns a new camera and leaves its argument alone.

export const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
export const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
export const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
export const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                a[0] * b[1] - a[1] * b[0]];
export const length = (a) => Math.hypot(a[0], a[1], a[2]);
export function normalize(a) {
    const l = length(a);
    return l > 0 ? scale(a, 1 / l) : [0, 0, 0];
}

const kDeg = Math.PI / 180;

/// v rotated by `angle` radians about the unit vector `axis` (Rodrigues' rotation formula).
export function rotateAbout(v, axis, angle) {
    const c = Math.cos(angle), s = Math.sin(angle);
    return add(add(scale(v, c), scale(cross(axis, v), s)), scale(axis, dot(axis, v) * (1 - c)));
}

/// The camera's orthonormal frame: `dir` (unit, towards the focal point), `right`, `up` (view up
/// made orthogonal to dir) and `distance` (position to focal point). A view up parallel to the
/// direction is replaced by the coordinate axis least aligned with it.
export function frame(cam) {
    const offset = sub(cam.focal_point, cam.position);
    const distance = length(offset);
    const dir = distance > 0 ? scale(offset, 1 / distance) : [0, 0, -1];
    let right = cross(dir, cam.view_up);
    if (length(right) < 1e-9 * Math.max(1, length(cam.view_up))) {
        const ax = dir.map(Math.abs);
        const least = ax.indexOf(Math.min(...ax));
        right = cross(dir, [0, 1, 2].map((i) => (i === least ? 1 : 0)));
    }
    right = normalize(right);
    return {dir, right, up: cross(right, dir), distance};
}

function copy(cam) {
    return {...cam, position: [...cam.position], focal_point: [...cam.focal_point],
            view_up: [...cam.view_up]};
}

/// Rotates the camera about its focal point: first `azimuthDeg` about view up (VTK's Azimuth:
/// positive moves the camera to its right), then `elevationDeg` about the right axis (VTK's
/// Elevation: positive moves it up); view up turns with the camera and is re-orthogonalised, so
/// the view passes over the poles without flipping.
export function orbit(cam, azimuthDeg, elevationDeg) {
    const f = frame(cam);
    let offset = sub(cam.position, cam.focal_point);
    offset = rotateAbout(offset, f.up, azimuthDeg * kDeg);
    const right = rotateAbout(f.right, f.up, azimuthDeg * kDeg);
    // VTK's Elevation turns about cross(-direction, up) = -right.
    offset = rotateAbout(offset, right, -elevationDeg * kDeg);
    let up = rotateAbout(f.up, right, -elevationDeg * kDeg);
    // Re-orthogonalise view up against the new direction (Gram-Schmidt) so rounding never drifts.
    const dir = normalize(scale(offset, -1));
    up = normalize(sub(up, scale(dir, dot(up, dir))));
    const out = copy(cam);
    out.position = add(cam.focal_point, offset);
    out.view_up = up;
    return out;
}

/// World units per display pixel at the focal distance, for a view `displayHeight` pixels high:
/// the height the view spans there (2 d tan(angle / 2), or 2 * parallel_scale) over the pixels.
export function worldPerPixel(cam, displayHeight) {
    const span = cam.parallel ? 2 * cam.parallel_scale
                              : 2 * frame(cam).distance * Math.tan(0.5 * cam.view_angle * kDeg);
    return span / Math.max(1, displayHeight);
}

/// Moves position and focal point together in the view plane so that the point under the cursor
/// at the focal distance follows a cursor motion of (dx, dy) display pixels (dy down, as in the
/// browser), on a view `displayHeight` pixels high.
export function pan(cam, dx, dy, displayHeight) {
    const f = frame(cam);
    const s = worldPerPixel(cam, displayHeight);
    // The scene follows the cursor, so the camera moves the other way: left for a cursor moving
    // right, up (along view up) for a cursor moving down the screen.
    const delta = add(scale(f.right, -dx * s), scale(f.up, dy * s));
    const out = copy(cam);
    out.position = add(cam.position, delta);
    out.focal_point = add(cam.focal_point, delta);
    return out;
}

/// The distance along unit vector `axis` that a cursor motion of (dx, dy) display pixels (dy
/// down) stands for, on a view `displayHeight` pixels high, at the focal distance: the motion's
/// part along the axis's image on the screen. An axis nearly along the view direction (its image
/// shorter than a fifth) moves with the vertical motion, up moving it away from the camera.
export function dragAlong(cam, axis, dx, dy, displayHeight) {
    const f = frame(cam);
    const s = worldPerPixel(cam, displayHeight);
    const px = dot(axis, f.right), py = -dot(axis, f.up);
    const pp = px * px + py * py;
    if (pp < 0.04) return -dy * s * Math.sign(dot(axis, f.dir) || 1);
    return (s * (dx * px + dy * py)) / pp;
}

/// Where world point p appears on a view `width` x `height` pixels: [x, y] in pixels from the
/// top left, as the renderer projects (VTK's vertical view angle, or parallel_scale half the
/// height); null for a point at or behind the camera's plane in perspective.
export function project(cam, p, width, height) {
    const f = frame(cam);
    const v = sub(p, cam.position);
    const z = dot(v, f.dir);
    let half;  // half the view's height in world units at p's depth
    if (cam.parallel) {
        half = cam.parallel_scale;
    } else {
        if (!(z > 1e-9 * Math.max(1, f.distance))) return null;
        half = z * Math.tan(0.5 * cam.view_angle * kDeg);
    }
    const aspect = width / Math.max(1, height);
    const x = dot(v, f.right) / (half * aspect), y = dot(v, f.up) / half;
    return [(0.5 + 0.5 * x) * width, (0.5 - 0.5 * y) * height];
}

/// The camera switched to parallel projection (on) or perspective (off), keeping what is seen at
/// the focal point: parallel_scale is half the height the perspective view spans there.
export function withProjection(cam, parallel) {
    const out = copy(cam);
    out.parallel = !!parallel;
    if (parallel && !cam.parallel)
        out.parallel_scale = frame(cam).distance * Math.tan(0.5 * cam.view_angle * kDeg);
    return out;
}

/// VTK's Dolly: factor > 1 moves the camera towards the focal point (the distance divided by
/// factor), < 1 away from it; in parallel projection the parallel scale is divided instead.
export function dolly(cam, factor) {
    if (!(factor > 0) || !Number.isFinite(factor)) return copy(cam);
    const out = copy(cam);
    if (cam.parallel) {
        out.parallel_scale = cam.parallel_scale / factor;
        return out;
    }
    const f = frame(cam);
    out.position = sub(cam.focal_point, scale(f.dir, f.distance / factor));
    return out;
}

/// VTK's trackball: a drag across the whole view width turns the camera 200 degrees of azimuth,
/// across its height 200 degrees of elevation (MotionFactor 10 times 20 / size).
export function dragRotation(dx, dy, width, height) {
    return {azimuth: (-200 * dx) / Math.max(1, width),
            elevation: (200 * dy) / Math.max(1, height)};
}

/// VTK's right-drag zoom: 1.1^(20 dy / height) with dy upwards (a drag up zooms in).
export function dragZoomFactor(dy, height) {
    return Math.pow(1.1, (-20 * dy) / Math.max(1, height));
}

/// VTK's wheel zoom: 1.1^2 per notch forward (away from the user, deltaY < 0); `notches` may be
/// fractional (trackpads).
export function wheelZoomFactor(notches) {
    return Math.pow(1.21, -notches);
}
