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
UVR_HOST_DEVICE inline Vec3d normalize(Vec3d a) {
    return a * (1.0 / sqrt(dot(a, a)));
}

}  // namespace uvr
