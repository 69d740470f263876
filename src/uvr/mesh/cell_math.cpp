// SPDX-License-Identifier: MIT
#include "uvr/mesh/cell_math.h"

#include <cmath>

#include "uvr/core/vec3d.h"

namespace uvr {

int nativeOrientation(CellKind k, const Vec3f* x) {
    // In double, relative to the cell's size (scale-free: a mesh of 1e-42, denormal in float,
    // or 1e30 is the unit mesh).
    const int n = kindCorners(k);
    Vec3d e[kMaxCellCorners];
    double size = 0.0;
    for (int i = 0; i < n; ++i) {
        if (!isFinite(x[i])) return 0;
        e[i] = toDouble(x[i]) - toDouble(x[0]);
        size = std::fmax(
            size, std::fmax(std::fabs(e[i].x), std::fmax(std::fabs(e[i].y), std::fabs(e[i].z))));
    }
    if (!(size > 0.0)) return 0;
    for (int i = 1; i < n; ++i) e[i] = e[i] * (1.0 / size);
    auto detAt = [&](Vec3f rst) {
        float w[kMaxCellCorners], dr[kMaxCellCorners], ds[kMaxCellCorners], dt[kMaxCellCorners];
        shapeFunctions(k, rst.x, rst.y, rst.z, w, dr, ds, dt);
        Vec3d jr, js, jt;
        for (int i = 1; i < n; ++i)
            jr = jr + e[i] * double(dr[i]), js = js + e[i] * double(ds[i]),
            jt = jt + e[i] * double(dt[i]);
        return dot(jr, cross(js, jt));
    };
    // The centre decides the sign; then the corners (a pyramid's apex, where the Jacobian
    // vanishes, at t = 0.5), each of that sign or folded by at most kNativeFold of it.
    const double centre = detAt(cellCentreParametric(k));
    if (!(std::fabs(centre) >= kNativeMinDet)) return 0;
    const int sign = centre > 0.0 ? 1 : -1;
    for (int i = 0; i < n; ++i) {
        Vec3f rst = cornerParametric(k, i);
        if (k == CellKind::Pyramid && i == 4) rst = Vec3f(0.5f, 0.5f, 0.5f);
        const double det = sign * detAt(rst);
        if (!(det >= -kNativeFold * std::fabs(centre))) return 0;  // also NaN
    }
    return sign;
}

}  // namespace uvr
