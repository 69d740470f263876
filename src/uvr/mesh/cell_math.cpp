// SPDX-License-Identifier: MIT
#include "uvr/mesh/cell_math.h"

#include <cmath>

namespace uvr {

int nativeOrientation(CellKind k, const Vec3f* x) {
    const int n = kindCorners(k);
    Vec3f e[kMaxCellCorners];
    e[0] = Vec3f(0.f);
    float size = 0.f;
    for (int i = 0; i < n; ++i) {
        if (!isFinite(x[i])) return 0;
        e[i] = x[i] - x[0];
        size = std::fmax(size, maxComponent(Vec3f(std::fabs(e[i].x), std::fabs(e[i].y),
                                                  std::fabs(e[i].z))));
    }
    const double minDet = 1e-6 * double(size) * size * size;
    if (!(minDet > 0.0)) return 0;
    int sign = 0;
    // The corners, then the centre (a pyramid's apex, where the Jacobian vanishes, at t = 0.5).
    for (int i = 0; i <= n; ++i) {
        Vec3f rst = i < n ? cornerParametric(k, i) : cellCentreParametric(k);
        if (k == CellKind::Pyramid && i == 4) rst = Vec3f(0.5f, 0.5f, 0.5f);
        Vec3f f, jr, js, jt;
        cellMap(k, e, rst, f, jr, js, jt);
        const double det = double(dot(jr, cross(js, jt)));
        const int s = det > minDet ? 1 : (det < -minDet ? -1 : 0);
        if (s == 0 || (sign != 0 && s != sign)) return 0;
        sign = s;
    }
    return sign;
}

}  // namespace uvr
