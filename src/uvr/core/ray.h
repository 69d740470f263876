// SPDX-License-Identifier: MIT
#pragma once

#include "uvr/core/vec.h"

namespace uvr {

/// Ray with origin and unit direction; points are org + t * dir.
struct Ray {
    Vec3f org;
    Vec3f dir;
    UVR_HOST_DEVICE Vec3f at(float t) const { return org + dir * t; }
};

}  // namespace uvr
