// SPDX-License-Identifier: MIT
#include "uvr/render/empty_frame.h"

#include <cmath>

#include "uvr/core/text.h"

namespace uvr {
namespace {

/// A value for a message (4 significant digits).
std::string fmt(double v) {
    return formatG(v, 4);
}

/// Largest opacity of the baked table over the values [lo, hi] (values beyond the table's range
/// take its end entries).
float maxOpacityOver(const FrameSetup& f, double lo, double hi) {
    const int n = static_cast<int>(f.tfTable.size());
    if (n == 0) return 0.f;
    const double width = double(f.rangeHi) - double(f.rangeLo);
    // Table position of a value, clamped to the table (a zero-width range maps to entry 0).
    auto position = [&](double v) {
        if (!(width > 0.0)) return 0.0;
        const double g = (v - f.rangeLo) / width * (n - 1);
        return g <= 0.0 ? 0.0 : (g >= n - 1 ? double(n - 1) : g);
    };
    // The entries the values interpolate between.
    const int a = static_cast<int>(std::floor(position(lo)));
    const int b = static_cast<int>(std::ceil(position(hi)));
    float best = 0.f;
    for (int i = a; i <= b; ++i) best = std::fmax(best, f.tfTable[i].w);
    return best;
}

}  // namespace

std::string explainEmptyFrame(const PreparedMesh& mesh, const RenderSettings& settings,
                              const RenderResult& result) {
    for (const Vec4f& p : result.image.pixels)
        if (p.w >= kEmptyPixelAlpha) return "";
    const FrameSetup& f = result.setup;
    // Does any pixel's ray meet the mesh's bounds?
    bool inView = false;
    const Bounds3f& box = mesh.tets.bounds;
    for (int y = 0; y < result.image.height && !inView; ++y)
        for (int x = 0; x < result.image.width && !inView; ++x) {
            const Ray ray = f.rays.ray(x + 0.5f, y + 0.5f);
            const Vec3f inv(1.f / ray.dir.x, 1.f / ray.dir.y, 1.f / ray.dir.z);
            float t0 = 0.f, t1 = INFINITY;
            inView = intersectBox(box, ray.org, inv, t0, t1);
        }
    if (!inView)
        return std::string(
                   "the image is empty: the mesh is not in view, or smaller than a pixel (no "
                   "pixel's ray meets its bounds); check the camera (`camera`, "
                   "`camera_position`/`camera_focal`, `azimuth`, `elevation`, ") +
               (f.camera.parallelProjection ? "`parallel_scale`" : "`view_angle`") + ")";
    // The values the kernels read: the blocks' vertices hold a tetrahedral mesh's point values
    // where `values` is not kept (a mesh read from a prepared cache).
    double lo = INFINITY, hi = -INFINITY;
    const auto extend = [&](float v) {
        if (std::isfinite(v)) lo = std::fmin(lo, v), hi = std::fmax(hi, v);
    };
    if (mesh.tets.values.empty())
        for (const BlockVertex& v : mesh.tets.blockVertices) extend(v.value);
    else
        for (float v : mesh.tets.values) extend(v);
    if (!(lo <= hi)) return "the image is empty: the field has no finite value";
    if (maxOpacityOver(f, lo, hi) > 0.f)
        return "the image is empty: every pixel's opacity is below half an 8-bit level; raise "
               "the opacity (`opacity`) or `opacity_unit`";
    // The transfer function is transparent over the field's values: say why.
    if (lo == hi)
        return "the image is empty: the field is constant (" + fmt(lo) +
               "), and the transfer function's opacity at that value is 0";
    if (settings.range &&
        (double(settings.range->second) < lo || double(settings.range->first) > hi))
        return "the image is empty: `range` " + fmt(settings.range->first) + "," +
               fmt(settings.range->second) + " misses the field's values [" + fmt(lo) + ", " +
               fmt(hi) +
               "], which all take the transfer function's end opacity (0 here); use a range "
               "inside the field's";
    return "the image is empty: the transfer function's opacity is 0 over all the field's "
           "values [" +
           fmt(lo) + ", " + fmt(hi) + "]; check `opacity` and `range`";
}

}  // namespace uvr
