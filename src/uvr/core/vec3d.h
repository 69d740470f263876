// SPDX-License-Identifier: MIT
#pragma once

#include <cmath>

#include "uvr/core/host_device.h"
#include "uvr/core/vec.h"

namespace uvr {

/// Double-precision vector for arithmetic whose results may lie beyond float's range or need
/// more than its precision (cameras of meshes near 1e38, ray-tetrahedron clipping).
struct Vec3d {
    double x = 0.0, y = 0.0, z = 0.0;
};

UVR_HOST_DEVICE inline Vec3d toDouble(Vec3f v) {
    return {v.x, v.y, v.z};
}
UVR_HOST_DEVICE inline Vec3d operator+(Vec3d a, Vec3d b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
UVR_HOST_DEVICE inline Vec3d operator-(Vec3d a, Vec3d b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
UVR_HOST_DEVICE inline Vec3d operator*(Vec3d a, double s) {
    return {a.x * s, a.y * s, a.z * s};
}
UVR_HOST_DEVICE inline double dot(Vec3d a, Vec3d b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
UVR_HOST_DEVICE inline Vec3d cross(Vec3d a, Vec3d b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// a * b and a + b each rounded on its own. CUDA's compiler fuses a product with the sum that
/// follows it (one rounding), which turns a difference of two equal products into the rounding
/// error of one instead of 0; these keep the host's exact zeros on the device. (x86-64 hosts
/// built without -mfma fuse nothing.)
UVR_HOST_DEVICE inline double mulRounded(double a, double b) {
#ifdef __CUDA_ARCH__
    return __dmul_rn(a, b);
#else
    return a * b;
#endif
}
UVR_HOST_DEVICE inline double addRounded(double a, double b) {
#ifdef __CUDA_ARCH__
    return __dadd_rn(a, b);
#else
    return a + b;
#endif
}
/// cross and dot with every product and sum rounded on its own (mulRounded, addRounded).
UVR_HOST_DEVICE inline Vec3d crossRounded(Vec3d a, Vec3d b) {
    return {addRounded(mulRounded(a.y, b.z), -mulRounded(a.z, b.y)),
            addRounded(mulRounded(a.z, b.x), -mulRounded(a.x, b.z)),
            addRounded(mulRounded(a.x, b.y), -mulRounded(a.y, b.x))};
}
UVR_HOST_DEVICE inline double dotRounded(Vec3d a, Vec3d b) {
    return addRounded(addRounded(mulRounded(a.x, b.x), mulRounded(a.y, b.y)), mulRounded(a.z, b.z));
}
UVR_HOST_DEVICE inline Vec3d normalize(Vec3d a) {
    return a * (1.0 / sqrt(dot(a, a)));
}

}  // namespace uvr
