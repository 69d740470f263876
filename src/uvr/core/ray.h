// SPDX-License-Identifier: MIT
#pragma once

#include <cmath>

#include "uvr/core/vec.h"

namespace uvr {

/// Ray with origin and unit direction; points are org + t * dir. It ends at tMax (opaque
/// geometry rendered elsewhere, given as a depth image: the integrators stop there).
struct Ray {
    Vec3f org;
    Vec3f dir;
    float tMax = INFINITY;
    UVR_HOST_DEVICE Vec3f at(float t) const { return org + dir * t; }
};

}  // namespace uvr
