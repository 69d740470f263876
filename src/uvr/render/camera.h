// SPDX-License-Identifier: MIT
#pragma once

#include <string>

#include "uvr/core/bounds.h"
#include "uvr/core/ray.h"
#include "uvr/core/vec.h"

namespace uvr {

/// A camera as ParaView describes one: position, focal point, view up and vertical view angle
/// in degrees (perspective projection).
struct Camera {
    Vec3f position{0.f, 0.f, 1.f};
    Vec3f focalPoint{0.f, 0.f, 0.f};
    Vec3f viewUp{0.f, 1.f, 0.f};
    float viewAngle = 30.f;
};

/// Smallest and largest vertical view angle in degrees a camera may have: narrower views make
/// every pixel's ray the same direction to float precision, and 180 degrees and beyond have no
/// image plane (ParaView allows up to 179).
inline constexpr float kMinViewAngle = 0.01f;
inline constexpr float kMaxViewAngle = 179.f;

/// ParaView's "reset camera" for the bounds: looking down -Z with +Y up, view angle 30 degrees,
/// the bounding sphere fitted to the view (also horizontally when aspect = width/height < 1).
Camera resetCamera(const Bounds3f& bounds, float aspect);

/// Rotates the camera position about the view-up axis through the focal point (ParaView's
/// Azimuth), then about the right axis (Elevation), both in degrees; view up is re-orthogonalised.
Camera orbitCamera(const Camera& camera, float azimuthDeg, float elevationDeg);

/// Loads a ParaView camera file (.pvcc, XML with CameraPosition, CameraFocalPoint, CameraViewUp,
/// CameraViewAngle); throws Error(Parse) naming the file and the missing or bad property.
Camera loadPvcc(const std::string& path);

/// Throws Error(Argument) when the camera cannot produce an image: non-finite values, position
/// equal to the focal point, view up parallel to the view direction, angle outside
/// [kMinViewAngle, kMaxViewAngle].
void validateCamera(const Camera& camera);

/// Precomputed primary-ray generator for a width x height image; plain data for CPU and GPU.
struct CameraRays {
    Vec3f origin;
    Vec3f topLeft;  ///< direction (unnormalised) through the top-left pixel corner
    Vec3f du;       ///< direction change per pixel to the right
    Vec3f dv;       ///< direction change per pixel downwards

    /// Ray through image position (px, py) in pixels from the top-left corner (pixel centres at
    /// +0.5), with unit direction.
    UVR_HOST_DEVICE Ray ray(float px, float py) const {
        Vec3f d = topLeft + du * px + dv * py;
        return {origin, normalize(d)};
    }
};

/// Builds the ray generator for a validated camera and image size.
CameraRays makeCameraRays(const Camera& camera, int width, int height);

}  // namespace uvr
