// SPDX-License-Identifier: MIT
#include "uvr/render/camera.h"

#include <gmock/gmock.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>

#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/core/vec3d.h"

namespace uvr {
namespace {

using ::testing::HasSubstr;
using uvr::testing::catchError;
using uvr::testing::expectVec;
using uvr::testing::pythonHas;
using uvr::testing::runCommand;
using uvr::testing::runPython;
using uvr::testing::scratchDir;
using uvr::testing::systemPython;
using uvr::testing::writeFile;

/// Relative tolerance for camera positions computed in float.
constexpr float kTol = 1e-5f;

float degrees(float rad) {
    return rad * 180.f / std::numbers::pi_v<float>;
}

float angleBetween(Vec3f a, Vec3f b) {
    return degrees(std::acos(std::clamp(dot(normalize(a), normalize(b)), -1.f, 1.f)));
}

Bounds3f boundsOf(Vec3f lo, Vec3f hi) {
    Bounds3f b;
    b.extend(lo);
    b.extend(hi);
    return b;
}

TEST(Camera, ResetFitsBoundingSphereLookingDownMinusZ) {
    Camera cam = resetCamera(boundsOf({-1, -1, -1}, {1, 1, 1}), 1.5f);
    float d = std::sqrt(3.f) / std::sin(15.f * std::numbers::pi_v<float> / 180.f);
    expectVec(cam.position, {0.f, 0.f, d}, kTol * d);
    expectVec(cam.focalPoint, {0.f, 0.f, 0.f}, 0.f);
    expectVec(cam.viewUp, {0.f, 1.f, 0.f}, 0.f);
    EXPECT_FLOAT_EQ(cam.viewAngle, 30.f);
    EXPECT_NO_THROW(validateCamera(cam));
}

TEST(Camera, ResetMatchesVtkRendererForWideAndTallImages) {
    if (!pythonHas("vtk")) GTEST_SKIP() << "system Python has no vtk";
    std::string dir = scratchDir();
    std::vector<double> v = runPython(dir, R"(
import vtk
for w, h in ((400, 200), (200, 400)):
    r = vtk.vtkRenderer()
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(r)
    win.SetSize(w, h)
    r.ResetCamera(-1, 2, -3, 4, 0, 1)
    c = r.GetActiveCamera()
    print(*c.GetPosition(), *c.GetFocalPoint(), *c.GetViewUp(), c.GetViewAngle())
)");
    ASSERT_EQ(v.size(), 20u);
    Bounds3f b = boundsOf({-1, -3, 0}, {2, 4, 1});
    float aspects[2] = {2.f, 0.5f};
    for (int k = 0; k < 2; ++k) {
        Camera cam = resetCamera(b, aspects[k]);
        const double* r = &v[10 * k];
        expectVec(cam.position, Vec3f(r[0], r[1], r[2]), 1e-4f, "position");
        expectVec(cam.focalPoint, Vec3f(r[3], r[4], r[5]), 1e-6f, "focal point");
        expectVec(cam.viewUp, Vec3f(r[6], r[7], r[8]), 1e-6f, "view up");
        EXPECT_FLOAT_EQ(cam.viewAngle, static_cast<float>(r[9]));
    }
    EXPECT_GT(resetCamera(b, 0.5f).position.z, resetCamera(b, 2.f).position.z);
}

TEST(Camera, ResetRejectsEmptyBoundsAndBadAspect) {
    EXPECT_EQ(catchError([] { resetCamera(Bounds3f{}, 1.f); }).kind(), ErrorKind::Argument);
    Bounds3f b = boundsOf({0, 0, 0}, {1, 1, 1});
    EXPECT_EQ(catchError([&] { resetCamera(b, 0.f); }).kind(), ErrorKind::Argument);
    EXPECT_EQ(catchError([&] { resetCamera(b, std::nanf("")); }).kind(), ErrorKind::Argument);
}

Vec3f f3(Vec3d v) {
    return Vec3f(float(v.x), float(v.y), float(v.z));
}

/// Pixel position (x, y) of point p in an image of rays (solving the ray equations).
std::pair<double, double> project(const CameraRays& r, bool parallel, Vec3f p) {
    // Perspective: [du dv -(p - o)] (x, y, s) = -topLeft; parallel: [oDu oDv dir] (x, y, t) =
    // p - origin.
    const Vec3d a = toDouble(parallel ? r.originDu : r.du),
                b = toDouble(parallel ? r.originDv : r.dv),
                c = parallel ? toDouble(r.topLeft) : (toDouble(p) - toDouble(r.origin)) * -1.0,
                rhs = parallel ? toDouble(p) - toDouble(r.origin) : toDouble(r.topLeft) * -1.0;
    const double det = dot(a, cross(b, c));
    return {dot(rhs, cross(b, c)) / det, dot(a, cross(rhs, c)) / det};
}

TEST(Camera, ClearColumnsKeepsTheBoundingSphereLeftOfThemAndCentred) {
    // Issue 35: a legend's columns at the right edge. The reset camera, turned, is moved back
    // and panned: the bounding sphere then projects into the columns left of them, its centre
    // in their middle. Points on the sphere: its poles along the image's axes and a ring.
    const Bounds3f b = boundsOf({-1.f, -0.5f, -2.f}, {3.f, 0.5f, 2.f});
    const Vec3d centre = (toDouble(b.lo) + toDouble(b.hi)) * 0.5;
    const double radius = 0.5 * std::sqrt(dot(toDouble(b.hi - b.lo), toDouble(b.hi - b.lo)));
    for (const auto& [w, h] : {std::pair{320, 240}, {200, 300}, {640, 240}})
        for (const bool parallel : {false, true})
            for (const int columns : {0, 60}) {
                SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h) + " columns " +
                             std::to_string(columns) + (parallel ? " parallel" : ""));
                Camera cam = orbitCamera(resetCamera(b, float(w) / h), 30.f, 20.f);
                cam.parallelProjection = parallel;
                const Camera moved = clearColumns(cam, w, h, columns);
                const CameraRays rays = makeCameraRays(moved, w, h);
                const auto [cx, cy] = project(rays, parallel, f3(centre));
                EXPECT_NEAR(cx, 0.5 * (w - columns), 1e-2);
                EXPECT_NEAR(cy, 0.5 * h, 1e-2);
                double minX = 1e9, maxX = -1e9, minY = 1e9, maxY = -1e9;
                const Vec3d dir = normalize(toDouble(moved.focalPoint - moved.position));
                const Vec3d right = normalize(cross(dir, toDouble(moved.viewUp)));
                const Vec3d up = cross(right, dir);
                // The silhouette: for perspective the ring where rays from the eye touch the
                // sphere (nearer the eye than the centre, and smaller), for parallel the great
                // circle across the view.
                const Vec3d eye = toDouble(moved.position), toEye = eye - centre;
                const double d2 = dot(toEye, toEye), k2 = radius * radius / d2;
                const Vec3d ringCentre = parallel ? centre : centre + toEye * k2;
                const double ring = parallel ? radius : radius * std::sqrt(1.0 - k2);
                const Vec3d a = normalize(cross(toEye, toDouble(moved.viewUp)));
                const Vec3d c = normalize(cross(toEye, a));
                for (int k = 0; k < 360; ++k) {
                    const double t = k * std::numbers::pi / 180.0;
                    const Vec3d q = parallel
                                        ? centre + (right * std::cos(t) + up * std::sin(t)) * ring
                                        : ringCentre + (a * std::cos(t) + c * std::sin(t)) * ring;
                    const auto [x, y] = project(rays, parallel, f3(q));
                    minX = std::min(minX, x), maxX = std::max(maxX, x);
                    minY = std::min(minY, y), maxY = std::max(maxY, y);
                }
                // The pan moves the sphere off the axis, where perspective stretches it a
                // little (half a pixel of 200 here): within 1% of the width.
                const double tol = parallel ? 0.01 : 0.01 * w;
                EXPECT_GE(minX, -tol);
                EXPECT_LE(maxX, w - columns + tol);
                EXPECT_GE(minY, -tol);
                EXPECT_LE(maxY, h + tol);
                // Tight: the reset fits the sphere to the height or to the columns left.
                EXPECT_TRUE(maxY - minY > h - 2 * tol - 1 ||
                            maxX - minX > w - columns - 2 * tol - 1);
                if (columns == 0) {
                    expectVec(moved.position, cam.position, 1e-5f);
                    expectVec(moved.focalPoint, cam.focalPoint, 1e-6f);
                }
            }
    Camera cam = resetCamera(b, 1.f);
    EXPECT_EQ(catchError([&] { clearColumns(cam, 100, 100, 100); }).kind(), ErrorKind::Argument);
    EXPECT_EQ(catchError([&] { clearColumns(cam, 100, 100, -1); }).kind(), ErrorKind::Argument);
}

TEST(Camera, CentreRayHitsFocalPointAndEdgesSpanTheViewAngle) {
    Camera cam;
    cam.position = {1.f, 2.f, 3.f};
    cam.focalPoint = {-2.f, 0.5f, 1.f};
    cam.viewUp = {0.f, 0.f, 1.f};
    cam.viewAngle = 40.f;
    const int w = 64, h = 48;
    CameraRays rays = makeCameraRays(cam, w, h);
    Vec3f dir = normalize(cam.focalPoint - cam.position);
    Ray centre = rays.ray(w / 2.f, h / 2.f);
    expectVec(centre.org, cam.position, 0.f);
    expectVec(centre.dir, dir, 1e-6f);
    // Top and bottom edge midpoints span the vertical view angle; left and right edges the
    // horizontal angle that the aspect ratio gives.
    EXPECT_NEAR(angleBetween(rays.ray(w / 2.f, 0.f).dir, rays.ray(w / 2.f, h).dir), 40.f, 1e-3f);
    float halfH = std::tan(20.f * std::numbers::pi_v<float> / 180.f);
    float horizontal = 2.f * degrees(std::atan(halfH * w / h));
    EXPECT_NEAR(angleBetween(rays.ray(0.f, h / 2.f).dir, rays.ray(w, h / 2.f).dir), horizontal,
                1e-3f);
    // Pixel (0, 0) is top-left: above the view direction (along view up) and to the left.
    Vec3f right = normalize(cross(dir, cam.viewUp));
    Vec3f topLeft = rays.ray(0.5f, 0.5f).dir;
    EXPECT_GT(dot(topLeft, cam.viewUp), dot(dir, cam.viewUp));
    EXPECT_LT(dot(topLeft, right), 0.f);
    EXPECT_NEAR(length(rays.ray(3.5f, 7.5f).dir), 1.f, 1e-6f);
    EXPECT_EQ(catchError([&] { makeCameraRays(cam, 0, 10); }).kind(), ErrorKind::Argument);
}

TEST(Camera, OrbitAzimuth90MovesToPlusX) {
    Camera cam;
    cam.position = {0.f, 0.f, 10.f};
    Camera a = orbitCamera(cam, 90.f, 0.f);
    expectVec(a.position, {10.f, 0.f, 0.f}, 1e-5f);
    expectVec(a.viewUp, {0.f, 1.f, 0.f}, 1e-6f);
    Camera e = orbitCamera(cam, 0.f, 90.f);  // over the pole: view up turns with the camera
    expectVec(e.position, {0.f, 10.f, 0.f}, 1e-5f);
    expectVec(e.viewUp, {0.f, 0.f, -1.f}, 1e-6f);
    EXPECT_NO_THROW(validateCamera(e));
}

TEST(Camera, OrbitMatchesVtkCameraAzimuthElevation) {
    if (!pythonHas("vtk")) GTEST_SKIP() << "system Python has no vtk";
    std::string dir = scratchDir();
    std::vector<double> v = runPython(dir, R"(
import vtk
for az, el in ((90, 0), (30, 20), (-70, -45), (200, 60)):
    c = vtk.vtkCamera()
    c.SetPosition(1, 2, 8)
    c.SetFocalPoint(0.5, -1, 0)
    c.SetViewUp(0.1, 1, 0)
    c.Azimuth(az)
    c.Elevation(el)
    c.OrthogonalizeViewUp()
    print(*c.GetPosition(), *c.GetViewUp())
)");
    ASSERT_EQ(v.size(), 24u);
    Camera cam;
    cam.position = {1.f, 2.f, 8.f};
    cam.focalPoint = {0.5f, -1.f, 0.f};
    cam.viewUp = {0.1f, 1.f, 0.f};
    float angles[4][2] = {{90, 0}, {30, 20}, {-70, -45}, {200, 60}};
    for (int k = 0; k < 4; ++k) {
        Camera o = orbitCamera(cam, angles[k][0], angles[k][1]);
        const double* r = &v[6 * k];
        std::string what = "orbit " + std::to_string(k);
        expectVec(o.position, Vec3f(r[0], r[1], r[2]), 1e-4f, what);
        expectVec(o.viewUp, Vec3f(r[3], r[4], r[5]), 1e-5f, what);
        EXPECT_NEAR(length(o.position - o.focalPoint), length(cam.position - cam.focalPoint),
                    1e-4f);
    }
}

TEST(Camera, ValidateRejectsDegenerateCameras) {
    EXPECT_NO_THROW(validateCamera(Camera{}));
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    struct Case {
        Camera cam;
        const char* what;
    };
    Camera c;
    std::vector<Case> cases;
    c = Camera{}, c.position.x = nan, cases.push_back({c, "non-finite"});
    c = Camera{}, c.focalPoint.z = inf, cases.push_back({c, "non-finite"});
    c = Camera{}, c.viewUp.y = nan, cases.push_back({c, "non-finite"});
    c = Camera{}, c.viewAngle = nan, cases.push_back({c, "non-finite"});
    c = Camera{}, c.focalPoint = c.position, cases.push_back({c, "equals the focal point"});
    c = Camera{}, c.viewUp = {0.f, 0.f, 2.f}, cases.push_back({c, "parallel"});
    c = Camera{}, c.viewUp = {0.f, 0.f, 0.f}, cases.push_back({c, "parallel"});
    c = Camera{}, c.viewAngle = 0.f, cases.push_back({c, "[0.01, 179]"});
    c = Camera{}, c.viewAngle = 1e-30f, cases.push_back({c, "[0.01, 179]"});
    c = Camera{}, c.viewAngle = 179.5f, cases.push_back({c, "[0.01, 179]"});
    c = Camera{}, c.viewAngle = 180.f, cases.push_back({c, "[0.01, 179]"});
    c = Camera{}, c.viewAngle = -10.f, cases.push_back({c, "[0.01, 179]"});
    for (const Case& k : cases) {
        Error e = catchError([&] { validateCamera(k.cam); });
        EXPECT_EQ(e.kind(), ErrorKind::Argument) << e.what();
        EXPECT_THAT(e.what(), HasSubstr(k.what));
    }
}

/// A .pvcc file as ParaView writes it, with the given camera properties.
std::string pvcc(const std::string& position, const std::string& angle = "30",
                 const std::string& up =
                     "0.0522244587063913\" /><Element index=\"1\" "
                     "value=\"0.99\"/><Element index=\"2\" value=\"0.1") {
    return R"(<?xml version="1.0"?>
<PVCameraConfiguration description="ParaView camera configuration" version="1.0">
  <Proxy group="views" type="RenderView" id="2076" servers="21">
    <Property name="CameraPosition" id="2076.CameraPosition" number_of_elements="3">
)" + position +
           R"(
    </Property>
    <Property name="CameraFocalPoint" id="2076.CameraFocalPoint" number_of_elements="3">
      <Element index="0" value="-0.445446427868706"/>
      <Element index="1" value="0.115471756220899"/>
      <Element index="2" value="-0.440184037664585"/>
    </Property>
    <Property name="CameraViewUp" id="2076.CameraViewUp" number_of_elements="3">
      <Element index="0" value=")" +
           up + R"("/>
    </Property>
    <Property name="CenterOfRotation" id="2076.CenterOfRotation" number_of_elements="3">
      <Element index="0" value="0"/>
      <Element index="1" value="0"/>
      <Element index="2" value="0"/>
    </Property>
    <Property name="CameraViewAngle" id="2076.CameraViewAngle" number_of_elements="1">
      <Element index="0" value=")" +
           angle + R"("/>
    </Property>
  <Property name="CameraParallelProjection" id="7.CameraParallelProjection" number_of_elements="1">
      <Element index="0" value="0"/>
      <Domain name="bool" id="2076.CameraParallelProjection.bool"/>
    </Property>
  </Proxy>
</PVCameraConfiguration>
)";
}

const char* kPosition = R"(      <Element index="0" value="7.11835691704117"/>
      <Element index="1" value="56.1347613281343"/>
      <Element index="2" value="6.60090036368214"/>)";

TEST(Camera, LoadsParaViewCameraFile) {
    std::string path = writeFile(scratchDir() + "/view.pvcc", pvcc(kPosition, "22.5"));
    Camera cam = loadPvcc(path);
    expectVec(cam.position, {7.11835691704117f, 56.1347613281343f, 6.60090036368214f}, 0.f);
    expectVec(cam.focalPoint, {-0.445446427868706f, 0.115471756220899f, -0.440184037664585f}, 0.f);
    expectVec(cam.viewUp, {0.0522244587063913f, 0.99f, 0.1f}, 0.f);
    EXPECT_FLOAT_EQ(cam.viewAngle, 22.5f);
}

TEST(Camera, PvccTextReadsBackToTheSameCamera) {
    Camera cam;
    cam.position = {1.f / 3.f, -2.5e7f, 7.125f};
    cam.focalPoint = {0.1f, 0.2f, -0.3f};
    cam.viewUp = {0.f, 0.f, 1.f};
    cam.viewAngle = 12.345f;
    for (bool parallel : {false, true}) {
        cam.parallelProjection = parallel;
        cam.parallelScale = 3.0e-3f;
        const std::string text = pvccText(cam);
        bool hasScale = false;
        const Camera back =
            parsePvcc(std::vector<char>(text.begin(), text.end()), "upload", &hasScale);
        EXPECT_TRUE(hasScale);
        expectVec(back.position, cam.position, 0.f, "position");
        expectVec(back.focalPoint, cam.focalPoint, 0.f, "focal point");
        expectVec(back.viewUp, cam.viewUp, 0.f, "view up");
        EXPECT_EQ(back.viewAngle, cam.viewAngle);
        EXPECT_EQ(back.parallelProjection, parallel);
        EXPECT_EQ(back.parallelScale, cam.parallelScale);
    }
    cam.viewUp = cam.focalPoint - cam.position;  // parallel to the view: no such file is written
    EXPECT_EQ(catchError([&] { pvccText(cam); }).kind(), ErrorKind::Argument);
    const std::string bad = "<PVCameraConfiguration>";
    EXPECT_THAT(catchError([&] {
                    parsePvcc({bad.begin(), bad.end()}, "the upload");
                }).what(),
                ::testing::HasSubstr("the upload"));
}

TEST(Camera, Utf16CameraFilesReadTheSameAndUtf32IsRefused) {
    // XML processors must read UTF-16 (XML 1.0, Sec. 4.3.3); expat does, with or without a
    // byte-order mark. A UTF-16 file that declares itself UTF-8 gets a hint.
    const std::string dir = scratchDir();
    const std::string text = pvcc(kPosition, "22.5");
    const auto utf16 = [](const std::string& ascii, bool bigEndian, bool bom) {
        std::string out = bom ? (bigEndian ? "\xFE\xFF" : "\xFF\xFE") : "";
        for (char c : ascii) out += bigEndian ? std::string{'\0', c} : std::string{c, '\0'};
        return out;
    };
    const Camera want = loadPvcc(writeFile(dir + "/utf8.pvcc", text));
    for (const bool be : {false, true})
        for (const bool bom : {false, true}) {
            const Camera got = loadPvcc(writeFile(dir + "/utf16.pvcc", utf16(text, be, bom)));
            expectVec(got.position, want.position, 0.f, "position");
            expectVec(got.viewUp, want.viewUp, 0.f, "view up");
            EXPECT_EQ(got.viewAngle, want.viewAngle);
        }
    std::string declared = text;
    declared.replace(0, 21, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    const std::string path = writeFile(dir + "/declared.pvcc", utf16(declared, false, true));
    const Error e = catchError([&] { loadPvcc(path); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_THAT(e.what(), HasSubstr(path + ": line 1: "));
    EXPECT_THAT(e.what(), HasSubstr("UTF-16 text; save the camera file as UTF-8"));
}

TEST(Camera, BadCameraFilesNameFileAndProperty) {
    std::string dir = scratchDir();
    std::string twoElements = R"(<Element index="0" value="1"/><Element index="1" value="2"/>)";
    std::string word = R"(<Element index="0" value="1"/><Element index="1" value="abc"/>
      <Element index="2" value="3"/>)";
    std::string missing = pvcc(kPosition);
    size_t from = missing.find("    <Property name=\"CameraViewUp\"");
    size_t to = missing.find("</Property>", from) + 12;
    missing.erase(from, to - from);
    std::string parallel = pvcc(kPosition);
    parallel.replace(parallel.find("value=\"0\"/>\n      <Domain"), 9, "value=\"1\"");
    std::string badScale = parallel;
    badScale.replace(badScale.find("  </Proxy>"), 0,
                     "    <Property name=\"CameraParallelScale\" number_of_elements=\"1\">\n"
                     "      <Element index=\"0\" value=\"-2\"/>\n    </Property>\n");
    std::string alongUp = pvcc(R"(<Element index="0" value="-0.445446427868706"/>
      <Element index="1" value="9"/>
      <Element index="2" value="-0.440184037664585"/>)",
                               "30",
                               "0\" /><Element index=\"1\" value=\"1\"/><Element "
                               "index=\"2\" value=\"0");
    std::string declared = pvcc(kPosition);
    declared.replace(declared.find("number_of_elements=\"3\""), 22, "number_of_elements=\"4\"");
    struct Case {
        const char* name;
        std::string text;
        ErrorKind kind;
        const char* where;
        const char* what;
    };
    const Case cases[] = {
        {"missing", missing, ErrorKind::Parse, "line 2: property CameraViewUp", "found none"},
        {"count", pvcc(twoElements), ErrorKind::Parse, "line 4: property CameraPosition",
         "expected 3 element(s), got 2"},
        {"word", pvcc(word), ErrorKind::Parse, "property CameraPosition",
         "element 1: expected a finite number, got \"abc\""},
        {"angle", pvcc(kPosition, "180"), ErrorKind::Parse, "line 2: ", "[0.01, 179] degrees"},
        {"tinyangle", pvcc(kPosition, "1e-30"), ErrorKind::Parse, "line 2: ", "got 1e-30"},
        // number_of_elements disagreeing with the elements present (was "expected 3 element(s),
        // got 3").
        {"declared", declared, ErrorKind::Parse, "line 4: property CameraPosition",
         "expected number_of_elements=\"3\", got \"4\""},
        // Character references put control characters into values: quoted escaped, one line.
        {"controls", pvcc(R"(<Element index="0" value="1"/><Element index="1" value="x&#10;y&#9;z"/>
      <Element index="2" value="3"/>)"),
         ErrorKind::Parse, "line 4: property CameraPosition", "got \"x\\ny\\tz\""},
        {"notxml", "CameraPosition 1 2 3\n", ErrorKind::Parse, "line 1", "expected XML"},
        {"unclosed", pvcc(kPosition).substr(0, 300), ErrorKind::Parse, "line ", "expected XML"},
        {"otherxml", "<?xml version=\"1.0\"?>\n<VTKFile/>\n", ErrorKind::Parse, "line 1",
         "PVCameraConfiguration"},
        {"parallel", parallel, ErrorKind::Parse, "line 25: property CameraParallelProjection",
         "parallel projection needs a <Property name=\"CameraParallelScale\">"},
        {"badscale", badScale, ErrorKind::Parse, "line 29: property CameraParallelScale",
         "expected a positive parallel scale (half the view height), got -2"},
        {"alongup", alongUp, ErrorKind::Parse, "line 14: property CameraViewUp",
         "parallel to the view direction from CameraPosition to CameraFocalPoint"},
        {"utf32", std::string("\xFF\xFE\0\0<\0\0\0", 8), ErrorKind::Parse, "byte 0",
         "UTF-32 text is not supported; save the camera file as UTF-8"},
    };
    for (const Case& c : cases) {
        std::string path = writeFile(dir + "/" + c.name + ".pvcc", c.text);
        Error e = catchError([&] { loadPvcc(path); });
        EXPECT_EQ(e.kind(), c.kind) << c.name << ": " << e.what();
        EXPECT_THAT(e.what(), HasSubstr(path + ": ")) << c.name;
        EXPECT_THAT(e.what(), HasSubstr(c.where)) << c.name;
        EXPECT_THAT(e.what(), HasSubstr(c.what)) << c.name;
        EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << c.name;
    }
    Error e = catchError([&] { loadPvcc(dir + "/absent.pvcc"); });
    EXPECT_EQ(e.kind(), ErrorKind::Io);
    EXPECT_THAT(e.what(), HasSubstr("absent.pvcc"));
}

TEST(Camera, ParallelCameraFilesLoadWithTheirScale) {
    // As ParaView writes them: CameraParallelScale always, CameraParallelProjection 0 or 1.
    std::string text = pvcc(kPosition);
    text.replace(text.find("  </Proxy>"), 0,
                 "    <Property name=\"CameraParallelScale\" number_of_elements=\"1\">\n"
                 "      <Element index=\"0\" value=\"2.5\"/>\n    </Property>\n");
    const std::string dir = scratchDir();
    bool hasScale = false;
    Camera perspective = loadPvcc(writeFile(dir + "/p.pvcc", text), &hasScale);
    EXPECT_FALSE(perspective.parallelProjection);
    EXPECT_TRUE(hasScale);
    EXPECT_FLOAT_EQ(perspective.parallelScale, 2.5f);
    text.replace(text.find("value=\"0\"/>\n      <Domain"), 9, "value=\"1\"");
    Camera parallel = loadPvcc(writeFile(dir + "/o.pvcc", text), &hasScale);
    EXPECT_TRUE(parallel.parallelProjection);
    EXPECT_FLOAT_EQ(parallel.parallelScale, 2.5f);
    expectVec(parallel.position, perspective.position, 0.f);
    loadPvcc(writeFile(dir + "/n.pvcc", pvcc(kPosition)), &hasScale);
    EXPECT_FALSE(hasScale);
}

TEST(Camera, ResetSetsTheParallelScaleAsVtkRendererDoes) {
    // vtkRenderer::ResetCamera: the bounding sphere's radius, over the aspect for tall images.
    const Bounds3f b = boundsOf({-1, -3, 0}, {2, 4, 1});
    const float radius = 0.5f * std::sqrt(9.f + 49.f + 1.f);
    EXPECT_FLOAT_EQ(resetCamera(b, 2.f).parallelScale, radius);
    EXPECT_FLOAT_EQ(resetCamera(b, 0.5f).parallelScale, radius / 0.5f);
    EXPECT_FALSE(resetCamera(b, 1.f).parallelProjection);
    if (!pythonHas("vtk")) GTEST_SKIP() << "system Python has no vtk";
    std::vector<double> v = runPython(scratchDir(), R"(
import vtk
for w, h in ((400, 200), (200, 400)):
    r = vtk.vtkRenderer()
    win = vtk.vtkRenderWindow()
    win.SetOffScreenRendering(1)
    win.AddRenderer(r)
    win.SetSize(w, h)
    r.GetActiveCamera().ParallelProjectionOn()
    r.ResetCamera(-1, 2, -3, 4, 0, 1)
    print(r.GetActiveCamera().GetParallelScale())
)");
    ASSERT_EQ(v.size(), 2u);
    EXPECT_NEAR(resetCamera(b, 2.f).parallelScale, v[0], 1e-5 * v[0]);
    EXPECT_NEAR(resetCamera(b, 0.5f).parallelScale, v[1], 1e-5 * v[1]);
}

TEST(Camera, ParallelRaysShareTheViewDirectionAndSpanTwiceTheScale) {
    Camera cam;
    cam.position = {1.f, 2.f, 3.f};
    cam.focalPoint = {-2.f, 0.5f, 1.f};
    cam.viewUp = {0.f, 0.f, 1.f};
    cam.parallelProjection = true;
    cam.parallelScale = 1.5f;
    const int w = 64, h = 48;
    const CameraRays rays = makeCameraRays(cam, w, h);
    const Vec3f dir = normalize(cam.focalPoint - cam.position);
    const Vec3f right = normalize(cross(dir, cam.viewUp));
    const Vec3f up = cross(right, dir);
    for (float px : {0.f, 0.5f, 31.f, 64.f})
        for (float py : {0.f, 47.5f, 48.f}) expectVec(rays.ray(px, py).dir, dir, 1e-6f);
    // The centre ray starts at the camera; the image plane is 2 scale high, 2 scale * aspect
    // wide, pixel (0, 0) top-left; origins lie on the plane through the camera.
    expectVec(rays.ray(w / 2.f, h / 2.f).org, cam.position, 1e-5f);
    expectVec(rays.ray(w / 2.f, 0.f).org - rays.ray(w / 2.f, h).org, up * 3.f, 1e-5f);
    expectVec(rays.ray(w, h / 2.f).org - rays.ray(0.f, h / 2.f).org, right * (3.f * w / h), 1e-5f);
    EXPECT_NEAR(dot(rays.ray(3.5f, 40.5f).org - cam.position, dir), 0.f, 1e-6f);
    // A near distance moves the plane forward along the view direction, nothing else.
    const CameraRays moved = makeCameraRays(cam, w, h, 2.0);
    expectVec(moved.ray(7.5f, 9.5f).org - rays.ray(7.5f, 9.5f).org, dir * 2.f, 1e-5f);
    // Refused: a non-positive or non-finite scale; an image plane beyond float range.
    for (float bad : {0.f, -1.f, std::numeric_limits<float>::infinity(), std::nanf("")}) {
        Camera c = cam;
        c.parallelScale = bad;
        const Error e = catchError([&] { makeCameraRays(c, w, h); });
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_THAT(e.what(), HasSubstr("parallel scale"));
    }
    Camera huge = cam;
    huge.parallelScale = 3e38f;
    EXPECT_THAT(catchError([&] { makeCameraRays(huge, w, h); }).what(),
                HasSubstr("beyond float32 range"));
    // The view angle means nothing to a parallel camera.
    Camera angle = cam;
    angle.viewAngle = 0.f;
    EXPECT_NO_THROW(validateCamera(angle));
}

TEST(Camera, PerspectiveRaysAllStartAtTheCamera) {
    Camera cam;
    cam.position = {1.f, 2.f, 3.f};
    cam.focalPoint = {-2.f, 0.5f, 1.f};
    const CameraRays rays = makeCameraRays(cam, 64, 48, 5.0);  // the near distance is ignored
    expectVec(rays.originDu, Vec3f(0.f), 0.f);
    expectVec(rays.originDv, Vec3f(0.f), 0.f);
    for (float px : {0.5f, 17.5f, 63.5f}) expectVec(rays.ray(px, 30.5f).org, cam.position, 0.f);
}

TEST(Camera, DefaultViewUpIsPlusYUnlessLookingAlongY) {
    const Vec3f y(0.f, 1.f, 0.f), z(0.f, 0.f, 1.f);
    expectVec(defaultViewUp({0.f, 0.f, 5.f}, {0.f, 0.f, 0.f}), y, 0.f);
    expectVec(defaultViewUp({3.f, 1.f, 0.f}, {0.f, 0.f, 0.f}), y, 0.f);
    expectVec(defaultViewUp({0.f, 5.f, 0.f}, {0.f, 0.f, 0.f}), z, 0.f);
    expectVec(defaultViewUp({1.f, -4.f, 1.f}, {1.f, 2.f, 1.f}), z, 0.f);
    EXPECT_TRUE(viewUpParallel({0.f, 5.f, 0.f}, {0.f, 0.f, 0.f}, y));
    EXPECT_TRUE(viewUpParallel({0.f, 5.f, 0.f}, {0.f, 0.f, 0.f}, Vec3f(0.f)));
    EXPECT_FALSE(viewUpParallel({0.f, 5.f, 0.f}, {0.f, 0.f, 0.f}, z));
    // The orbit keeps the projection and scale.
    Camera c;
    c.parallelProjection = true;
    c.parallelScale = 4.f;
    const Camera o = orbitCamera(c, 30.f, 20.f);
    EXPECT_TRUE(o.parallelProjection);
    EXPECT_EQ(o.parallelScale, 4.f);
}

}  // namespace
}  // namespace uvr
