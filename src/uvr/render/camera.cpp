// SPDX-License-Identifier: MIT
#include "uvr/render/camera.h"

#include <expat.h>

#include <array>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <numbers>
#include <sstream>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/text.h"
#include "uvr/core/vec3d.h"

namespace uvr {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

/// Largest camera file read; real .pvcc files are about 2 kilobytes.
constexpr std::uint64_t kMaxPvccBytes = 16ull << 20;

/// Rotates v about the unit axis by angle radians (Rodrigues' rotation formula, right-handed).
Vec3d rotate(Vec3d v, Vec3d axis, double angle) {
    const double c = std::cos(angle), s = std::sin(angle);
    return v * c + cross(axis, v) * s + axis * (dot(axis, v) * (1.0 - c));
}

/// v in float; throws Error(Argument) naming `what` when a component lies beyond float's range.
Vec3f toFloat(Vec3d v, const std::string& what) {
    for (double c : {v.x, v.y, v.z})
        if (!(std::fabs(c) <= double(FLT_MAX))) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "%.3g", c);
            throwError(ErrorKind::Argument, "",
                       what + " would lie at " + buf +
                           ", beyond float32 range (3.4e38): rescale the mesh or give "
                           "`camera_position` and `camera_focal`");
        }
    return {float(v.x), float(v.y), float(v.z)};
}

std::string formatVec(Vec3f v) {
    std::ostringstream os;
    os << "(" << v.x << ", " << v.y << ", " << v.z << ")";
    return os.str();
}

/// One <Property> of a .pvcc file: its element values by index and where it started.
struct PvccProperty {
    std::map<int, std::string> elements;
    long declaredCount = -1;
    std::uint64_t line = 0;
};

/// Expat parsing state for a .pvcc file.
struct PvccParser {
    XML_Parser parser = nullptr;
    std::string path;
    std::map<std::string, PvccProperty> properties;
    std::string current;  ///< name of the open <Property>, "" outside one
    bool sawRoot = false;
    std::uint64_t rootLine = 1;  ///< line of <PVCameraConfiguration>
    std::string error;           ///< first error found by a handler (without file and line)
    std::uint64_t errorLine = 0;

    void fail(const std::string& message) {
        if (error.empty()) {
            error = message;
            errorLine = XML_GetCurrentLineNumber(parser);
        }
        XML_StopParser(parser, XML_FALSE);
    }
};

const char* attribute(const XML_Char** attrs, const char* name) {
    for (int i = 0; attrs[i]; i += 2) {
        if (std::string(attrs[i]) == name) return attrs[i + 1];
    }
    return nullptr;
}

void XMLCALL onStart(void* data, const XML_Char* name, const XML_Char** attrs) {
    auto* p = static_cast<PvccParser*>(data);
    std::string tag = name;
    if (tag == "PVCameraConfiguration") {
        p->sawRoot = true;
        p->rootLine = XML_GetCurrentLineNumber(p->parser);
    }
    if (tag == "Property") {
        const char* propName = attribute(attrs, "name");
        p->current = propName ? propName : "";
        if (p->current.empty()) return;
        PvccProperty& prop = p->properties[p->current];
        prop = PvccProperty{};
        prop.line = XML_GetCurrentLineNumber(p->parser);
        if (const char* n = attribute(attrs, "number_of_elements")) {
            char* end = nullptr;
            long count = std::strtol(n, &end, 10);
            if (end == n || *end != '\0' || count < 0) {
                p->fail("property " + printableShort(p->current) +
                        ": expected an integer number_of_elements, got \"" + printableShort(n) +
                        "\"");
                return;
            }
            prop.declaredCount = count;
        }
    } else if (tag == "Element" && !p->current.empty()) {
        const char* index = attribute(attrs, "index");
        const char* value = attribute(attrs, "value");
        char* end = nullptr;
        long i = index ? std::strtol(index, &end, 10) : -1;
        if (!index || end == index || *end != '\0' || i < 0 || i > 1000) {
            p->fail("property " + printableShort(p->current) +
                    ": expected an Element with an index, got \"" +
                    printableShort(index ? index : "") + "\"");
            return;
        }
        if (!value) {
            p->fail("property " + printableShort(p->current) + ": Element " + std::to_string(i) +
                    " has no value");
            return;
        }
        p->properties[p->current].elements[static_cast<int>(i)] = value;
    }
}

void XMLCALL onEnd(void* data, const XML_Char* name) {
    auto* p = static_cast<PvccParser*>(data);
    if (std::string(name) == "Property") p->current.clear();
}

/// Values of a required property with exactly count numeric elements.
std::vector<double> propertyValues(const PvccParser& p, const std::string& name, int count) {
    auto it = p.properties.find(name);
    if (it == p.properties.end()) {
        throwParseError(p.path, atLine(p.rootLine) + ": property " + name,
                        "expected a <Property name=\"" + name + "\"> with " +
                            std::to_string(count) + " element(s), found none");
    }
    const PvccProperty& prop = it->second;
    std::string where = atLine(prop.line) + ": property " + name;
    if (prop.declaredCount >= 0 && prop.declaredCount != count) {
        throwParseError(p.path, where,
                        "expected number_of_elements=\"" + std::to_string(count) + "\", got \"" +
                            std::to_string(prop.declaredCount) + "\"");
    }
    if (static_cast<int>(prop.elements.size()) != count) {
        throwParseError(p.path, where,
                        "expected " + std::to_string(count) + " element(s), got " +
                            std::to_string(prop.elements.size()));
    }
    std::vector<double> values;
    for (int i = 0; i < count; ++i) {
        auto e = prop.elements.find(i);
        if (e == prop.elements.end()) {
            throwParseError(p.path, where,
                            "expected an Element with index " + std::to_string(i) + ", found none");
        }
        const char* text = e->second.c_str();
        char* end = nullptr;
        errno = 0;
        double v = std::strtod(text, &end);
        if (end == text || *end != '\0' || errno == ERANGE || !std::isfinite(v)) {
            throwParseError(p.path, where,
                            "element " + std::to_string(i) + ": expected a finite number, got \"" +
                                printableShort(e->second) + "\"");
        }
        values.push_back(v);
    }
    return values;
}

Vec3f toVec3(const std::vector<double>& v) {
    return {static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2])};
}

}  // namespace

Camera clearColumns(const Camera& camera, int width, int height, int columns) {
    if (!(width > 0 && height > 0 && columns >= 0 && columns < width))
        throwError(ErrorKind::Argument, "",
                   "cannot keep " + std::to_string(columns) + " columns clear of " +
                       std::to_string(width) + "x" + std::to_string(height) + " pixels");
    // resetCamera's distance is radius / sin(angle / 2), its parallel scale radius (/ aspect),
    // with the angle narrowed below aspect 1: the ratio of two fits does not depend on the bounds.
    const double a = double(width) / height, narrow = double(width - columns) / height;
    const double half = 0.5 * double(camera.viewAngle) * kDegToRad;
    const auto fitHalfAngle = [&](double aspect) {
        return aspect < 1.0 ? std::atan(std::tan(half) * aspect) : half;
    };
    Camera c = camera;
    const Vec3d focal = toDouble(c.focalPoint), back = toDouble(c.position) - focal;
    const double distance = std::sqrt(dot(back, back));
    double perPixel = 0.0;  // file units per pixel at the focal point, after the move back
    if (c.parallelProjection) {
        const double wide = (narrow < 1.0 ? 1.0 / narrow : 1.0) / (a < 1.0 ? 1.0 / a : 1.0);
        c.parallelScale = static_cast<float>(std::fmin(c.parallelScale * wide, double(FLT_MAX)));
        perPixel = 2.0 * double(c.parallelScale) / height;
    } else {
        const double far = std::sin(fitHalfAngle(a)) / std::sin(fitHalfAngle(narrow));
        c.position = toFloat(focal + back * far, "the moved camera");
        perPixel = 2.0 * distance * far * std::tan(half) / height;
    }
    // The pan: half the columns to the right, so the volume moves left by as much.
    const Vec3d right = normalize(cross(back * -1.0, toDouble(c.viewUp)));
    const Vec3d pan = right * (0.5 * columns * perPixel);
    c.position = toFloat(toDouble(c.position) + pan, "the panned camera");
    c.focalPoint = toFloat(focal + pan, "the panned camera's focal point");
    return c;
}

Camera resetCamera(const Bounds3f& bounds, float aspect) {
    if (bounds.empty() || !isFinite(bounds.lo) || !isFinite(bounds.hi)) {
        throwError(ErrorKind::Argument, "",
                   "cannot reset the camera to empty or non-finite bounds");
    }
    if (!(aspect > 0.f) || !std::isfinite(aspect)) {
        throwError(
            ErrorKind::Argument, "",
            "camera aspect (width / height) must be positive, got " + std::to_string(aspect));
    }
    // vtkRenderer::ResetCamera: fit the bounding sphere into the view angle (the horizontal one
    // when the image is taller than wide); a zero radius becomes 0.5 as in VTK. In double: the
    // diagonal of bounds beyond 1.8e19 overflows float, the camera of bounds near 1e38 too.
    const Vec3d lo = toDouble(bounds.lo), hi = toDouble(bounds.hi);
    double radius = std::sqrt(dot(hi - lo, hi - lo));
    radius = radius == 0.0 ? 0.5 : 0.5 * radius;
    Camera cam;
    cam.viewAngle = 30.f;
    double angle = cam.viewAngle * kDegToRad;
    if (aspect < 1.f) angle = 2.0 * std::atan(std::tan(0.5 * angle) * aspect);
    double distance = radius / std::sin(0.5 * angle);
    const Vec3d focal = (lo + hi) * 0.5;
    cam.focalPoint = toFloat(focal, "the reset camera's focal point");
    cam.position = toFloat(focal + Vec3d{0.0, 0.0, distance}, "the reset camera");
    cam.viewUp = Vec3f(0.f, 1.f, 0.f);
    // vtkRenderer::ResetCamera: the parallel scale shows the sphere's diameter vertically, or
    // horizontally when the image is taller than wide.
    const double scale = aspect < 1.f ? radius / aspect : radius;
    cam.parallelScale = static_cast<float>(std::fmin(scale, double(FLT_MAX)));
    return cam;
}

namespace {

/// Sine of the angle between the view direction from position to focal point and `up` (0 for a
/// zero up), in double; the points must be distinct.
double viewUpSine(Vec3f position, Vec3f focalPoint, Vec3f upF) {
    const Vec3d offset = toDouble(focalPoint) - toDouble(position);
    const Vec3d dir = offset * (1.0 / std::sqrt(dot(offset, offset)));
    const Vec3d up = toDouble(upF);
    const double upLen = std::sqrt(dot(up, up));
    if (!(upLen > 0.0)) return 0.0;
    const Vec3d sine = cross(dir, up * (1.0 / upLen));
    return std::sqrt(dot(sine, sine));
}

/// Smallest sine between view up and view direction that orients an image.
constexpr double kMinViewUpSine = 1e-4;

/// Whether two finite points are far enough apart to define a view direction: more than two
/// float spacings of their coordinates (in double: the offset of float points near 1e38
/// overflows float and that of points 1e-30 apart underflows its square).
bool pointsDistinct(Vec3f position, Vec3f focalPoint) {
    const Vec3d offset = toDouble(focalPoint) - toDouble(position);
    const double dist = std::sqrt(dot(offset, offset));
    const double scale = std::max(maxComponent(vmax(position, -position)),
                                  maxComponent(vmax(focalPoint, -focalPoint)));
    return dist > 0.0 && dist > 2.0 * FLT_EPSILON * scale;
}

/// Whether every component of v lies within float's range.
bool fitsFloat(Vec3d v) {
    return std::fabs(v.x) <= double(FLT_MAX) && std::fabs(v.y) <= double(FLT_MAX) &&
           std::fabs(v.z) <= double(FLT_MAX);
}

}  // namespace

bool viewUpParallel(Vec3f position, Vec3f focalPoint, Vec3f up) {
    return !(viewUpSine(position, focalPoint, up) >= kMinViewUpSine);
}

Vec3f defaultViewUp(Vec3f position, Vec3f focalPoint) {
    const Vec3f y(0.f, 1.f, 0.f);
    return viewUpParallel(position, focalPoint, y) ? Vec3f(0.f, 0.f, 1.f) : y;
}

Camera orbitCamera(const Camera& camera, float azimuthDeg, float elevationDeg) {
    validateCamera(camera);
    Camera out = camera;
    // In double: the offset between float points can exceed float's range.
    const Vec3d focal = toDouble(camera.focalPoint);
    Vec3d offset = toDouble(camera.position) - focal;
    Vec3d up = normalize(toDouble(camera.viewUp));
    // vtkCamera::Azimuth: rotate the position about view up (as given) through the focal point.
    offset = rotate(offset, up, azimuthDeg * kDegToRad);
    const Vec3d dir = normalize(offset * -1.0);
    up = normalize(up - dir * dot(up, dir));
    // vtkCamera::Elevation: rotate about the negated right axis, so positive angles move the
    // camera towards view up. View up turns with it (the orthogonalised up VTK gives for angles
    // within +-90 degrees, and well defined at the poles).
    const Vec3d axis = normalize(cross(up, dir));
    offset = rotate(offset, axis, elevationDeg * kDegToRad);
    up = normalize(rotate(up, axis, elevationDeg * kDegToRad));
    out.position = toFloat(focal + offset, "the orbited camera");
    out.viewUp = {float(up.x), float(up.y), float(up.z)};
    return out;
}

Camera loadPvcc(const std::string& path, bool* hasParallelScale) {
    return parsePvcc(readFileBytes(path, kMaxPvccBytes, "camera file"), path, hasParallelScale);
}

Camera parsePvcc(const std::vector<char>& bytes, const std::string& path, bool* hasParallelScale) {
    if (bytes.size() > kMaxPvccBytes)
        throwError(ErrorKind::Resource, path,
                   "camera file of " + std::to_string(bytes.size()) + " bytes: more than " +
                       std::to_string(kMaxPvccBytes));
    // XML processors read UTF-8 and UTF-16 (expat converts UTF-16 to UTF-8), not UTF-32.
    const char* wide = wideTextEncoding(bytes.data(), bytes.size());
    if (wide && std::string(wide) == "UTF-32")
        throwParseError(path, atByte(0),
                        "UTF-32 text is not supported; save the camera file as UTF-8");

    PvccParser state;
    state.path = path;
    state.parser = XML_ParserCreate(nullptr);
    if (!state.parser) throwError(ErrorKind::Resource, path, "cannot create an XML parser");
    XML_SetUserData(state.parser, &state);
    XML_SetElementHandler(state.parser, onStart, onEnd);
    XML_Status status =
        XML_Parse(state.parser, bytes.data(), static_cast<int>(bytes.size()), XML_TRUE);
    std::string xmlError;
    std::uint64_t xmlLine = 0;
    if (status == XML_STATUS_ERROR && state.error.empty()) {
        xmlError = XML_ErrorString(XML_GetErrorCode(state.parser));
        xmlLine = XML_GetCurrentLineNumber(state.parser);
    }
    XML_ParserFree(state.parser);
    state.parser = nullptr;
    if (!state.error.empty()) throwParseError(path, atLine(state.errorLine), state.error);
    if (!xmlError.empty()) {
        throwParseError(path, atLine(xmlLine),
                        "expected XML (a ParaView camera configuration), got: " + xmlError +
                            (wide ? std::string(" (the file is ") + wide +
                                        " text; save the camera file as UTF-8)"
                                  : std::string()));
    }
    if (!state.sawRoot) {
        throwParseError(path, atLine(1),
                        "expected a <PVCameraConfiguration> element (a ParaView .pvcc file)");
    }

    Camera cam;
    cam.position = toVec3(propertyValues(state, "CameraPosition", 3));
    cam.focalPoint = toVec3(propertyValues(state, "CameraFocalPoint", 3));
    cam.viewUp = toVec3(propertyValues(state, "CameraViewUp", 3));
    cam.viewAngle = static_cast<float>(propertyValues(state, "CameraViewAngle", 1)[0]);
    // ParaView writes CameraParallelScale always and CameraParallelProjection as 0 or 1; a file
    // without them is a perspective camera.
    cam.parallelProjection = state.properties.count("CameraParallelProjection") &&
                             propertyValues(state, "CameraParallelProjection", 1)[0] != 0.0;
    const bool hasScale = state.properties.count("CameraParallelScale") > 0;
    if (hasParallelScale) *hasParallelScale = hasScale;
    if (hasScale) {
        const double scale = propertyValues(state, "CameraParallelScale", 1)[0];
        if (cam.parallelProjection && !(scale > 0.0 && scale <= double(FLT_MAX)))
            throwParseError(
                path,
                atLine(state.properties["CameraParallelScale"].line) +
                    ": property CameraParallelScale",
                "expected a positive parallel scale (half the view height), got " +
                    printableShort(state.properties["CameraParallelScale"].elements[0]));
        if (std::fabs(scale) <= double(FLT_MAX)) cam.parallelScale = static_cast<float>(scale);
    } else if (cam.parallelProjection) {
        throwParseError(path,
                        atLine(state.properties["CameraParallelProjection"].line) +
                            ": property CameraParallelProjection",
                        "parallel projection needs a <Property name=\"CameraParallelScale\"> "
                        "(half the view height), found none");
    }
    // A view up parallel to the view direction is the file's: named with its property.
    if (isFinite(cam.position) && isFinite(cam.focalPoint) && isFinite(cam.viewUp) &&
        pointsDistinct(cam.position, cam.focalPoint) &&
        viewUpParallel(cam.position, cam.focalPoint, cam.viewUp))
        throwParseError(path,
                        atLine(state.properties["CameraViewUp"].line) + ": property CameraViewUp",
                        "view up " + formatVec(cam.viewUp) +
                            " is zero or parallel to the view direction from CameraPosition to "
                            "CameraFocalPoint; give a view up across it");
    try {
        validateCamera(cam);
    } catch (const Error& e) {
        throwParseError(path, atLine(state.rootLine), e.what());
    }
    return cam;
}

void validateCamera(const Camera& camera) {
    if (!isFinite(camera.position) || !isFinite(camera.focalPoint) || !isFinite(camera.viewUp) ||
        !std::isfinite(camera.viewAngle)) {
        throwError(ErrorKind::Argument, "",
                   "camera has non-finite values: position " + formatVec(camera.position) +
                       ", focal point " + formatVec(camera.focalPoint) + ", view up " +
                       formatVec(camera.viewUp) + ", angle " + std::to_string(camera.viewAngle));
    }
    if (!pointsDistinct(camera.position, camera.focalPoint)) {
        throwError(ErrorKind::Argument, "",
                   "camera position " + formatVec(camera.position) +
                       " equals the focal point; expected distinct points");
    }
    if (viewUpParallel(camera.position, camera.focalPoint, camera.viewUp)) {
        const Vec3d offset = toDouble(camera.focalPoint) - toDouble(camera.position);
        const Vec3d dir = offset * (1.0 / std::sqrt(dot(offset, offset)));
        throwError(ErrorKind::Argument, "",
                   "camera view up " + formatVec(camera.viewUp) +
                       " is zero or parallel to the view direction " +
                       formatVec({float(dir.x), float(dir.y), float(dir.z)}) +
                       "; give a view up across it");
    }
    if (camera.parallelProjection) {
        if (!std::isfinite(camera.parallelScale) || !(camera.parallelScale > 0.f)) {
            std::ostringstream os;
            os << "camera parallel scale (half the view height) must be positive, got "
               << camera.parallelScale;
            throwError(ErrorKind::Argument, "", os.str());
        }
    } else if (!(camera.viewAngle >= kMinViewAngle && camera.viewAngle <= kMaxViewAngle)) {
        std::ostringstream os;
        os << "camera view angle must be in [" << kMinViewAngle << ", " << kMaxViewAngle
           << "] degrees, got " << camera.viewAngle;
        throwError(ErrorKind::Argument, "", os.str());
    }
}

CameraRays makeCameraRays(const Camera& camera, int width, int height, double nearDistance) {
    validateCamera(camera);
    if (width <= 0 || height <= 0) {
        throwError(ErrorKind::Argument, "",
                   "image size must be positive, got " + std::to_string(width) + " x " +
                       std::to_string(height));
    }
    // Pinhole camera with the image plane at unit distance along the view direction (the
    // directions in double: the offset may lie beyond float's range).
    const Vec3d dirD = normalize(toDouble(camera.focalPoint) - toDouble(camera.position));
    const Vec3d rightD = normalize(cross(dirD, toDouble(camera.viewUp)));
    const Vec3d upD = cross(rightD, dirD);
    const Vec3f dir(float(dirD.x), float(dirD.y), float(dirD.z));
    const Vec3f right(float(rightD.x), float(rightD.y), float(rightD.z));
    const Vec3f up(float(upD.x), float(upD.y), float(upD.z));
    CameraRays rays;
    if (camera.parallelProjection) {
        // Orthographic: the image plane spans 2 parallelScale vertically (VTK's convention),
        // every ray along the view direction from the plane nearDistance in front of the camera.
        // Its centre is placed from the focal point, which lies near the mesh where the camera
        // may be far out and coarsely resolved (in double until the corner is known to fit).
        const double halfH = camera.parallelScale;
        const double halfW = halfH * double(width) / double(height);
        const double nearD = nearDistance > 0.0 ? nearDistance : 0.0;
        const Vec3d offset = toDouble(camera.focalPoint) - toDouble(camera.position);
        const double distance = std::sqrt(dot(offset, offset));
        const Vec3d corner =
            toDouble(camera.focalPoint) + dirD * (nearD - distance) - rightD * halfW + upD * halfH;
        const Vec3d stepU = rightD * (2.0 * halfW / double(width));
        const Vec3d stepV = upD * (-2.0 * halfH / double(height));
        const Vec3d far = corner + stepU * double(width) + stepV * double(height);
        if (!fitsFloat(corner) || !fitsFloat(far)) {
            std::ostringstream os;
            os << "the parallel camera's image plane (parallel scale " << camera.parallelScale
               << ") would reach beyond float32 range (3.4e38): use a smaller parallel scale";
            throwError(ErrorKind::Argument, "", os.str());
        }
        rays.origin = Vec3f(float(corner.x), float(corner.y), float(corner.z));
        rays.originDu = Vec3f(float(stepU.x), float(stepU.y), float(stepU.z));
        rays.originDv = Vec3f(float(stepV.x), float(stepV.y), float(stepV.z));
        rays.topLeft = dir;
        rays.du = rays.dv = Vec3f(0.f);
        return rays;
    }
    float halfH = static_cast<float>(std::tan(0.5 * camera.viewAngle * kDegToRad));
    float halfW = halfH * static_cast<float>(width) / static_cast<float>(height);
    rays.origin = camera.position;
    rays.topLeft = dir - right * halfW + up * halfH;
    rays.du = right * (2.f * halfW / static_cast<float>(width));
    rays.dv = up * (-2.f * halfH / static_cast<float>(height));
    rays.originDu = rays.originDv = Vec3f(0.f);
    return rays;
}

std::string pvccText(const Camera& camera) {
    validateCamera(camera);
    std::string out =
        "<?xml version=\"1.0\"?>\n"
        "<PVCameraConfiguration description=\"ParaView camera configuration\" version=\"1.0\">\n"
        "  <Proxy group=\"views\" type=\"RenderView\" id=\"4531\" servers=\"21\">\n";
    // %.9g: every float reads back to itself.
    auto property = [&](const char* name, std::initializer_list<double> values) {
        char line[200];
        std::snprintf(line, sizeof line,
                      "    <Property name=\"%s\" id=\"4531.%s\" number_of_elements=\"%zu\">\n",
                      name, name, values.size());
        out += line;
        int i = 0;
        for (double v : values) {
            std::snprintf(line, sizeof line, "      <Element index=\"%d\" value=\"%.9g\"/>\n", i++,
                          v);
            out += line;
        }
        out += "    </Property>\n";
    };
    auto vec = [&](const char* name, Vec3f v) { property(name, {v.x, v.y, v.z}); };
    vec("CameraPosition", camera.position);
    vec("CameraFocalPoint", camera.focalPoint);
    vec("CameraViewUp", camera.viewUp);
    property("CameraViewAngle", {camera.viewAngle});
    property("CameraParallelScale", {camera.parallelScale});
    property("CameraParallelProjection", {camera.parallelProjection ? 1.0 : 0.0});
    out += "  </Proxy>\n</PVCameraConfiguration>\n";
    return out;
}

}  // namespace uvr
