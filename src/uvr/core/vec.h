// SPDX-License-Identifier: MIT
#pragma once

#include <cmath>

#include "uvr/core/host_device.h"

namespace uvr {

/// Three-component float vector used for positions, directions and colours.
struct Vec3f {
    float x = 0.f, y = 0.f, z = 0.f;

    UVR_HOST_DEVICE constexpr Vec3f() = default;
    UVR_HOST_DEVICE constexpr Vec3f(float a, float b, float c) : x(a), y(b), z(c) {}
    UVR_HOST_DEVICE constexpr explicit Vec3f(float s) : x(s), y(s), z(s) {}
    UVR_HOST_DEVICE constexpr float operator[](int i) const {
        return i == 0 ? x : (i == 1 ? y : z);
    }
    UVR_HOST_DEVICE float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

UVR_HOST_DEVICE constexpr Vec3f operator+(Vec3f a, Vec3f b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
UVR_HOST_DEVICE constexpr Vec3f operator-(Vec3f a, Vec3f b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
UVR_HOST_DEVICE constexpr Vec3f operator-(Vec3f a) {
    return {-a.x, -a.y, -a.z};
}
UVR_HOST_DEVICE constexpr Vec3f operator*(Vec3f a, Vec3f b) {
    return {a.x * b.x, a.y * b.y, a.z * b.z};
}
UVR_HOST_DEVICE constexpr Vec3f operator*(Vec3f a, float s) {
    return {a.x * s, a.y * s, a.z * s};
}
UVR_HOST_DEVICE constexpr Vec3f operator*(float s, Vec3f a) {
    return {a.x * s, a.y * s, a.z * s};
}
UVR_HOST_DEVICE constexpr Vec3f operator/(Vec3f a, float s) {
    return {a.x / s, a.y / s, a.z / s};
}
UVR_HOST_DEVICE inline Vec3f& operator+=(Vec3f& a, Vec3f b) {
    a = a + b;
    return a;
}
UVR_HOST_DEVICE inline Vec3f& operator-=(Vec3f& a, Vec3f b) {
    a = a - b;
    return a;
}
UVR_HOST_DEVICE inline Vec3f& operator*=(Vec3f& a, float s) {
    a = a * s;
    return a;
}
UVR_HOST_DEVICE constexpr bool operator==(Vec3f a, Vec3f b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

/// Dot product.
UVR_HOST_DEVICE constexpr float dot(Vec3f a, Vec3f b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
/// Cross product (right-handed).
UVR_HOST_DEVICE constexpr Vec3f cross(Vec3f a, Vec3f b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// Euclidean length.
UVR_HOST_DEVICE inline float length(Vec3f a) {
    return sqrtf(dot(a, a));
}
/// Unit vector in the direction of a; a must be non-zero.
UVR_HOST_DEVICE inline Vec3f normalize(Vec3f a) {
    return a * (1.f / length(a));
}
/// Minimum as one instruction (b when either is NaN); fminf is a libm call on the host.
UVR_HOST_DEVICE inline float minf(float a, float b) {
    return a < b ? a : b;
}
/// Maximum as one instruction (b when either is NaN).
UVR_HOST_DEVICE inline float maxf(float a, float b) {
    return a > b ? a : b;
}
/// Component-wise minimum.
UVR_HOST_DEVICE inline Vec3f vmin(Vec3f a, Vec3f b) {
    return {minf(a.x, b.x), minf(a.y, b.y), minf(a.z, b.z)};
}
/// Component-wise maximum.
UVR_HOST_DEVICE inline Vec3f vmax(Vec3f a, Vec3f b) {
    return {maxf(a.x, b.x), maxf(a.y, b.y), maxf(a.z, b.z)};
}
/// Largest component.
UVR_HOST_DEVICE inline float maxComponent(Vec3f a) {
    return maxf(a.x, maxf(a.y, a.z));
}
/// True when every component is finite.
UVR_HOST_DEVICE inline bool isFinite(Vec3f a) {
#if defined(__CUDA_ARCH__)
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
#else
    return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z);
#endif
}

/// Four-component float vector, used for RGBA colours.
struct Vec4f {
    float x = 0.f, y = 0.f, z = 0.f, w = 0.f;
    UVR_HOST_DEVICE constexpr Vec4f() = default;
    UVR_HOST_DEVICE constexpr Vec4f(float a, float b, float c, float d) : x(a), y(b), z(c), w(d) {}
    UVR_HOST_DEVICE constexpr Vec3f xyz() const { return {x, y, z}; }
    UVR_HOST_DEVICE constexpr float operator[](int i) const {
        return i == 0 ? x : (i == 1 ? y : (i == 2 ? z : w));
    }
};
UVR_HOST_DEVICE constexpr Vec4f operator+(Vec4f a, Vec4f b) {
    return {a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w};
}
UVR_HOST_DEVICE constexpr Vec4f operator-(Vec4f a, Vec4f b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w};
}
UVR_HOST_DEVICE constexpr Vec4f operator*(Vec4f a, float s) {
    return {a.x * s, a.y * s, a.z * s, a.w * s};
}

}  // namespace uvr
