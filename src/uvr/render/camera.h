// SPDX-License-Identifier: MIT
#pragma once

#include <string>
#include <vector>

#include "uvr/core/bounds.h"
#include "uvr/core/ray.h"
#include "uvr/core/vec.h"

namespace uvr {

/// A camera as ParaView describes one: position, focal point, view up, and either the vertical
/// view angle in degrees (perspective projection) or, with parallelProjection, the parallel
/// scale: half the image height in world units (ParaView's CameraParallelScale). In parallel
/// projection every ray has the view direction and starts on the plane through the position
/// perpendicular to it (VTK's near clipping plane never lies behind the camera): what lies
/// behind that plane is not seen, as in ParaView.
struct Camera {
    Vec3f position{0.f, 0.f, 1.f};
    Vec3f focalPoint{0.f, 0.f, 0.f};
    Vec3f viewUp{0.f, 1.f, 0.f};
    float viewAngle = 30.f;           ///< perspective only
    bool parallelProjection = false;  ///< ParaView's CameraParallelProjection
    float parallelScale = 1.f;        ///< parallel only: half the image height (VTK's default 1)
};

/// Smallest and largest vertical view angle in degrees a camera may have: narrower views make
/// every pixel's ray the same direction to float precision, and 180 degrees and beyond have no
/// image plane (ParaView allows up to 179).
inline constexpr float kMinViewAngle = 0.01f;
inline constexpr float kMaxViewAngle = 179.f;

/// ParaView's "reset camera" for the bounds: looking down -Z with +Y up, view angle 30 degrees,
/// the bounding sphere fitted to the view (also horizontally when aspect = width/height < 1).
/// The parallel scale is set as vtkRenderer::ResetCamera sets it: the bounding sphere's radius
/// (divided by the aspect when it is below 1), so switching to parallel projection shows the
/// whole sphere; parallelProjection stays off.
Camera resetCamera(const Bounds3f& bounds, float aspect);

/// A camera fitted as resetCamera fits one to an image of width x height (then turned or
/// zoomed), moved back along its view direction (its parallel scale widened) as far as the
/// reset fitting width - columns columns would have placed it, and panned (position and focal
/// point moved sideways, as ParaView's pan) so that the volume is centred in the columns left
/// of the image's last `columns`: room at the right edge for a legend (issue 35). Moved back
/// only where the bounding sphere does not fit those columns already. Throws Error(Argument)
/// unless 0 <= columns < width.
Camera clearColumns(const Camera& camera, int width, int height, int columns);

/// Whether the view up `up` is zero or too close to parallel to the view direction from
/// `position` to `focalPoint` to orient an image (the test validateCamera applies; the points
/// must be distinct).
bool viewUpParallel(Vec3f position, Vec3f focalPoint, Vec3f up);

/// The view up a camera takes when none is given: +Y (ParaView's default), or +Z where +Y is
/// parallel to the view direction (ParaView's "look along +Y/-Y" buttons use +Z up).
Vec3f defaultViewUp(Vec3f position, Vec3f focalPoint);

/// Rotates the camera position about the view-up axis through the focal point (ParaView's
/// Azimuth), then about the right axis (Elevation), both in degrees; view up is re-orthogonalised.
Camera orbitCamera(const Camera& camera, float azimuthDeg, float elevationDeg);

/// Loads a ParaView camera file (.pvcc, XML with CameraPosition, CameraFocalPoint, CameraViewUp,
/// CameraViewAngle, and optionally CameraParallelProjection and CameraParallelScale, which
/// parallel projection needs); throws Error(Parse) naming the file and the missing or bad
/// property. hasParallelScale (when given) says whether the file held CameraParallelScale.
Camera loadPvcc(const std::string& path, bool* hasParallelScale = nullptr);

/// loadPvcc of a camera file held in memory (an upload); `source` names it in errors.
Camera parsePvcc(const std::vector<char>& bytes, const std::string& source,
                 bool* hasParallelScale = nullptr);

/// The camera as a ParaView camera file (.pvcc) that loadPvcc (and ParaView's "Load Camera
/// Configuration") reads back to the same camera: position, focal point, view up, view angle,
/// parallel scale and projection, each float written to read back exactly. Throws
/// Error(Argument) for a camera validateCamera refuses.
std::string pvccText(const Camera& camera);

/// Throws Error(Argument) when the camera cannot produce an image: non-finite values, position
/// equal to the focal point, view up parallel to the view direction, angle outside
/// [kMinViewAngle, kMaxViewAngle] (perspective), parallel scale not positive (parallel).
void validateCamera(const Camera& camera);

/// Precomputed primary-ray generator for a width x height image; plain data for CPU and GPU.
/// Perspective: every ray starts at the camera (originDu = originDv = 0) and its direction
/// varies over the image. Parallel: every ray has the view direction (du = dv = 0) and its
/// origin varies over the image plane. One formula serves both, with no branch.
struct CameraRays {
    Vec3f origin;    ///< origin of the ray through the top-left pixel corner
    Vec3f topLeft;   ///< direction (unnormalised) through the top-left pixel corner
    Vec3f du;        ///< direction change per pixel to the right
    Vec3f dv;        ///< direction change per pixel downwards
    Vec3f originDu;  ///< origin change per pixel to the right (parallel projection)
    Vec3f originDv;  ///< origin change per pixel downwards (parallel projection)

    /// Ray through image position (px, py) in pixels from the top-left corner (pixel centres at
    /// +0.5), with unit direction.
    UVR_HOST_DEVICE Ray ray(float px, float py) const {
        Vec3f d = topLeft + du * px + dv * py;
        return {origin + originDu * px + originDv * py, normalize(d)};
    }
};

/// Builds the ray generator for a validated camera and image size. Parallel projection: the
/// rays start on the plane `nearDistance` (>= 0) in front of the camera along the view
/// direction (the frame setup moves it up to the mesh, where nothing in between is seen, so a
/// far camera keeps the sample positions precise); perspective ignores it.
CameraRays makeCameraRays(const Camera& camera, int width, int height, double nearDistance = 0.0);

}  // namespace uvr
