// SPDX-License-Identifier: MIT
#include "vtkUvrVolumeMapper.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <optional>
#include <vector>

#include "uvr/mesh/io/vtk_cells.h"
#include "uvr/uvr.h"
#include "vtkCamera.h"
#include "vtkCellArray.h"
#include "vtkCellArrayIterator.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataArray.h"
#include "vtkDataSet.h"
#include "vtkIdTypeArray.h"
#include "vtkObjectFactory.h"
#include "vtkOpenGLQuadHelper.h"
#include "vtkOpenGLRenderWindow.h"
#include "vtkOpenGLShaderCache.h"
#include "vtkOpenGLState.h"
#include "vtkPiecewiseFunction.h"
#include "vtkPoints.h"
#include "vtkRenderer.h"
#include "vtkScalarsToColors.h"
#include "vtkShaderProgram.h"
#include "vtkTextureObject.h"
#include "vtkUnstructuredGrid.h"
#include "vtkVolume.h"
#include "vtkVolumeProperty.h"
#include "vtk_glew.h"

vtkStandardNewMacro(vtkUvrVolumeMapper);

namespace {

/// Control points a ParaView transfer function is sampled at: VTK evaluates its own colour
/// spaces, midpoints and sharpness, the library interpolates linearly between the samples.
constexpr int kTfSamples = 1024;

/// The full-screen pass that blends the frame over the viewport (vtkOpenGLQuadHelper's vertex
/// shader gives texCoord over the viewport).
constexpr const char* kBlitFragmentShader = R"(//VTK::System::Dec
in vec2 texCoord;
uniform sampler2D source;
//VTK::Output::Dec
void main() { gl_FragData[0] = texture2D(source, texCoord); }
)";

/// FNV-1a over raw bytes, eight at a time: tells whether a new data set has the geometry
/// already prepared.
std::uint64_t hashBytes(const void* data, std::size_t n, std::uint64_t h) {
    const auto* p = static_cast<const unsigned char*>(data);
    std::size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        std::uint64_t word;
        std::memcpy(&word, p + i, 8);
        h = (h ^ word) * 1099511628211ull;
    }
    for (; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

}  // namespace

struct vtkUvrVolumeMapper::Internals {
    uvr::RenderSettings settings;  ///< the vocabulary's settings as the panel set them
    uvr::RendererOptions options;
    int vectorMode = vtkScalarsToColors::MAGNITUDE;
    int vectorComponent = 0;

    // What is prepared.
    std::unique_ptr<uvr::Mesh> mesh;  ///< geometry and the prepared field's array
    std::unique_ptr<uvr::Renderer> renderer;
    std::uint64_t geometryKey = 0;
    /// The grid, its points' and cells' modification times when geometryKey was last worked
    /// out: the hash is taken again only when one of them changes, not at every frame.
    std::array<std::uintptr_t, 4> geometryStamp{};
    std::uint64_t stampedKey = 0;
    std::string fieldKey;  ///< array, association, component, values' modification time
    uvr::Association association = uvr::Association::Point;  ///< of the prepared field
    bool optionsChanged = true;
    /// The modification time of the input and the mapper when preparing last failed: the
    /// failure is reported once, not at every frame, until either changes.
    vtkMTimeType failedStamp = 0;

    std::string report = "{}";
    vtkNew<vtkTextureObject> texture;
    std::unique_ptr<vtkOpenGLQuadHelper> quad;  ///< draws the texture over the viewport
    std::vector<unsigned char> upload;          ///< the frame as 8-bit RGBA, rows from the bottom
};

vtkUvrVolumeMapper::vtkUvrVolumeMapper() : internals_(std::make_unique<Internals>()) {
    internals_->options.forAuto = true;
}

vtkUvrVolumeMapper::~vtkUvrVolumeMapper() = default;

void vtkUvrVolumeMapper::SetUvrSetting(const std::string& name, const nlohmann::json& value) {
    try {
        uvr::applySetting(internals_->settings, name, value);
        this->Modified();
    } catch (const std::exception& e) {
        vtkErrorMacro(<< "uvr Volume: " << e.what());
    }
}

void vtkUvrVolumeMapper::SetUvrDevice(const std::string& device) {
    try {
        const uvr::Device d = uvr::parseDevice(device, "Device");
        if (d != internals_->options.device) {
            internals_->options.device = d;
            internals_->optionsChanged = true;
            this->Modified();
        }
    } catch (const std::exception& e) {
        vtkErrorMacro(<< "uvr Volume: " << e.what());
    }
}

void vtkUvrVolumeMapper::SetUvrSplitCells(bool split) {
    if (split != internals_->options.splitCells) {
        internals_->options.splitCells = split;
        internals_->optionsChanged = true;
        this->Modified();
    }
}

void vtkUvrVolumeMapper::SetUvrClipPlane(bool on, const double origin[3], const double normal[3]) {
    auto& planes = internals_->settings.clipPlanes;
    planes.clear();
    if (on) {
        uvr::ClipPlane p;
        p.origin = {float(origin[0]), float(origin[1]), float(origin[2])};
        p.normal = {float(normal[0]), float(normal[1]), float(normal[2])};
        planes.push_back(p);
    }
    this->Modified();
}

void vtkUvrVolumeMapper::SetUvrIsoSurfaces(const std::vector<double>& values, double opacity) {
    auto& isos = internals_->settings.isoSurfaces;
    isos.clear();
    for (double v : values) {
        uvr::IsoSurface s;
        s.value = float(v);
        s.opacity = float(opacity);
        isos.push_back(s);
    }
    this->Modified();
}

void vtkUvrVolumeMapper::SetUvrVectorMode(int mode, int component) {
    if (mode != internals_->vectorMode || component != internals_->vectorComponent) {
        internals_->vectorMode = mode;
        internals_->vectorComponent = component;
        this->Modified();
    }
}

const std::string& vtkUvrVolumeMapper::LastReport() const {
    return internals_->report;
}

namespace {

/// The grid's points and cells in the library's layout (VTK's cell types, corner nodes of
/// quadratic cells, polyhedra from their face streams; 2D cells dropped with a note).
std::unique_ptr<uvr::Mesh> meshOf(vtkUnstructuredGrid* grid) {
    auto mesh = std::make_unique<uvr::Mesh>();
    const vtkIdType np = grid->GetNumberOfPoints();
    mesh->points.resize(std::size_t(np));
    vtkDataArray* pts = grid->GetPoints() ? grid->GetPoints()->GetData() : nullptr;
    for (vtkIdType i = 0; i < np; ++i) {
        double p[3];
        pts->GetTuple(i, p);
        mesh->points[std::size_t(i)] = {float(p[0]), float(p[1]), float(p[2])};
    }
    uvr::VtkCellArrays cells;
    const vtkIdType nc = grid->GetNumberOfCells();
    cells.types.resize(std::size_t(nc));
    cells.offsets.reserve(std::size_t(nc) + 1);
    cells.offsets.push_back(0);
    vtkIdTypeArray* faces = grid->GetFaces();
    vtkIdTypeArray* faceLocations = grid->GetFaceLocations();
    if (faces && faceLocations) {
        cells.polyhedronFaces = uvr::PolyhedronFaces::Separate;
        cells.faceOffsets.push_back(0);
    }
    auto it = vtk::TakeSmartPointer(grid->GetCells()->NewIterator());
    vtkIdType c = 0;
    for (it->GoToFirstCell(); !it->IsDoneWithTraversal(); it->GoToNextCell(), ++c) {
        vtkIdType n = 0;
        const vtkIdType* ids = nullptr;
        it->GetCurrentCell(n, ids);
        cells.types[std::size_t(c)] = grid->GetCellType(c);
        cells.connectivity.insert(cells.connectivity.end(), ids, ids + n);
        cells.offsets.push_back(std::int64_t(cells.connectivity.size()));
        if (cells.polyhedronFaces == uvr::PolyhedronFaces::Separate) {
            const vtkIdType at = faceLocations->GetValue(c);
            if (at >= 0) {
                // The stream [nFaces, n0, ids..., n1, ids...] of this polyhedron.
                vtkIdType k = at;
                const vtkIdType nFaces = faces->GetValue(k++);
                cells.faces.push_back(nFaces);
                for (vtkIdType f = 0; f < nFaces; ++f) {
                    const vtkIdType m = faces->GetValue(k++);
                    cells.faces.push_back(m);
                    for (vtkIdType j = 0; j < m; ++j) cells.faces.push_back(faces->GetValue(k++));
                }
            }
            cells.faceOffsets.push_back(std::int64_t(cells.faces.size()));
        }
    }
    uvr::appendVtkCells(cells, *mesh, "the ParaView input");
    return mesh;
}

/// A key that changes when the grid's points or cells change.
std::uint64_t geometryKeyOf(vtkUnstructuredGrid* grid) {
    std::uint64_t h = 1469598103934665603ull;
    const vtkIdType np = grid->GetNumberOfPoints(), nc = grid->GetNumberOfCells();
    h = hashBytes(&np, sizeof np, h);
    h = hashBytes(&nc, sizeof nc, h);
    if (vtkDataArray* pts = grid->GetPoints() ? grid->GetPoints()->GetData() : nullptr)
        h = hashBytes(pts->GetVoidPointer(0),
                      std::size_t(pts->GetNumberOfValues()) * std::size_t(pts->GetDataTypeSize()),
                      h);
    vtkCellArray* cells = grid->GetCells();
    for (vtkDataArray* a : {static_cast<vtkDataArray*>(cells->GetOffsetsArray()),
                            static_cast<vtkDataArray*>(cells->GetConnectivityArray())})
        h = hashBytes(a->GetVoidPointer(0),
                      std::size_t(a->GetNumberOfValues()) * std::size_t(a->GetDataTypeSize()), h);
    if (vtkDataArray* types = grid->GetCellTypesArray())
        h = hashBytes(types->GetVoidPointer(0), std::size_t(types->GetNumberOfValues()), h);
    return h;
}

/// A value's position in the map's range [lo, hi] (log-scaled when the map is).
double positionIn(double v, double lo, double hi, bool logScale) {
    if (logScale) return (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo));
    return (v - lo) / (hi - lo);
}

/// ParaView's colour and opacity functions as the library's transfer function, point for
/// point, as `uvr render` reads a ParaView colour-map export: where every node has the default
/// midpoint and sharpness, the colour space is one the library has (RGB, Lab, Diverging) and
/// the nodes lie in the map's range. Otherwise none.
std::optional<uvr::TransferFunction> tfFromNodes(vtkColorTransferFunction* ctf,
                                                 vtkPiecewiseFunction* pwf, const double range[2],
                                                 bool logScale) {
    uvr::TransferFunction tf;
    switch (ctf->GetColorSpace()) {
        case VTK_CTF_RGB:
            tf.colorSpace = uvr::ColorSpace::RGB;
            break;
        case VTK_CTF_LAB:
            tf.colorSpace = uvr::ColorSpace::Lab;
            break;
        case VTK_CTF_DIVERGING:
            tf.colorSpace = uvr::ColorSpace::Diverging;
            break;
        default:
            return std::nullopt;
    }
    const double lo = range[0], hi = range[1];
    if (!(hi > lo)) return std::nullopt;
    const auto inRange = [](double t) { return t >= -1e-6 && t <= 1.0 + 1e-6; };
    for (int i = 0; i < ctf->GetSize(); ++i) {
        double n[6];  // x, r, g, b, midpoint, sharpness
        ctf->GetNodeValue(i, n);
        const double t = positionIn(n[0], lo, hi, logScale);
        if (n[4] != 0.5 || n[5] != 0.0 || !inRange(t)) return std::nullopt;
        tf.colors.push_back(
            {float(std::clamp(t, 0.0, 1.0)), {float(n[1]), float(n[2]), float(n[3])}});
    }
    if (pwf) {
        for (int i = 0; i < pwf->GetSize(); ++i) {
            double n[4];  // x, opacity, midpoint, sharpness
            pwf->GetNodeValue(i, n);
            const double t = positionIn(n[0], lo, hi, logScale);
            if (n[2] != 0.5 || n[3] != 0.0 || !inRange(t)) return std::nullopt;
            tf.opacities.push_back({float(std::clamp(t, 0.0, 1.0)), float(n[1])});
        }
    } else {
        tf.opacities = {{0.f, 1.f}, {1.f, 1.f}};
    }
    if (tf.colors.empty() || tf.opacities.empty()) return std::nullopt;
    return tf;
}

/// The transfer function the library renders: ParaView's colour and opacity functions node for
/// node where the library has their interpolation (tfFromNodes), else sampled at kTfSamples
/// values over the colour map's range (log-spaced on a log scale), where VTK evaluates its own
/// colour spaces, midpoints and sharpness.
uvr::TransferFunction tfOf(vtkColorTransferFunction* ctf, vtkPiecewiseFunction* pwf,
                           const double range[2], bool logScale) {
    std::optional<uvr::TransferFunction> nodes = tfFromNodes(ctf, pwf, range, logScale);
    uvr::TransferFunction tf = nodes ? std::move(*nodes) : uvr::TransferFunction{};
    if (!nodes) {
        const double lo = logScale ? std::log10(range[0]) : range[0];
        const double hi = logScale ? std::log10(range[1]) : range[1];
        for (int i = 0; i < kTfSamples; ++i) {
            const double t = double(i) / (kTfSamples - 1);
            double v = lo + t * (hi - lo);
            if (logScale) v = std::pow(10.0, v);
            // The continuous function, as VTK's volume mappers read it: ParaView's colour map
            // is a vtkDiscretizableColorTransferFunction whose own GetColor returns the colour
            // of its table's bin when "Discretize" is on (its default).
            double rgb[3];
            ctf->vtkColorTransferFunction::GetColor(v, rgb);
            tf.colors.push_back({float(t), {float(rgb[0]), float(rgb[1]), float(rgb[2])}});
            tf.opacities.push_back({float(t), pwf ? float(pwf->GetValue(v)) : 1.f});
        }
    }
    tf.name = "ParaView";
    tf.logScale = logScale;
    const double* nan = ctf->GetNanColor();
    tf.nanColor = {float(nan[0]), float(nan[1]), float(nan[2])};
    tf.nanOpacity = 0.f;  // VTK's volume mappers draw no NaN values
    return tf;
}

/// The camera of the view in the library's terms.
uvr::Camera cameraOf(vtkCamera* cam) {
    uvr::Camera c;
    const double* p = cam->GetPosition();
    const double* f = cam->GetFocalPoint();
    const double* u = cam->GetViewUp();
    c.position = {float(p[0]), float(p[1]), float(p[2])};
    c.focalPoint = {float(f[0]), float(f[1]), float(f[2])};
    c.viewUp = {float(u[0]), float(u[1]), float(u[2])};
    c.viewAngle = float(cam->GetViewAngle());
    c.parallelProjection = cam->GetParallelProjection() != 0;
    c.parallelScale = float(cam->GetParallelScale());
    return c;
}

}  // namespace

bool vtkUvrVolumeMapper::Prepare(vtkDataSet* input, void (*progress)(void*, const char*, double),
                                 void* client) {
    Internals& in = *internals_;
    const vtkMTimeType stamp = std::max(input ? input->GetMTime() : 0, this->GetMTime());
    if (stamp == in.failedStamp) return false;
    try {
        auto* grid = vtkUnstructuredGrid::SafeDownCast(input);
        if (!grid) {
            throw uvr::Error(uvr::ErrorKind::Unsupported,
                             std::string("uvr Volume renders unstructured grids, not ") +
                                 (input ? input->GetClassName() : "no data"));
        }
        int cellFlag = 0;
        vtkDataArray* array =
            vtkAbstractMapper::GetScalars(input, this->ScalarMode, this->ArrayAccessMode,
                                          this->ArrayId, this->ArrayName, cellFlag);
        if (!array) {
            throw uvr::Error(uvr::ErrorKind::Argument,
                             std::string("no array to render") +
                                 (this->ArrayName && this->ArrayName[0]
                                      ? std::string(": '") + this->ArrayName + "' is not found"
                                      : std::string(": colour the data set by a point or cell "
                                                    "array")));
        }
        const int components = array->GetNumberOfComponents();
        int component = -1;  // the magnitude
        if (components > 1 && in.vectorMode == vtkScalarsToColors::COMPONENT)
            component = std::min(in.vectorComponent, components - 1);
        if (components == 1) component = 0;
        const std::string fieldKey = std::string(array->GetName() ? array->GetName() : "") +
                                     (cellFlag ? ":cell:" : ":point:") + std::to_string(component) +
                                     ":" + std::to_string(array->GetMTime()) + ":" +
                                     std::to_string(reinterpret_cast<std::uintptr_t>(array));
        const std::array<std::uintptr_t, 4> geometryStamp{
            reinterpret_cast<std::uintptr_t>(grid),
            std::uintptr_t(grid->GetPoints() ? grid->GetPoints()->GetMTime() : 0),
            std::uintptr_t(grid->GetCells() ? grid->GetCells()->GetMTime() : 0),
            std::uintptr_t(grid->GetCellTypesArray() ? grid->GetCellTypesArray()->GetMTime() : 0)};
        if (geometryStamp != in.geometryStamp) {
            in.stampedKey = geometryKeyOf(grid);
            in.geometryStamp = geometryStamp;
        }
        const std::uint64_t geometryKey = in.stampedKey;
        const bool sameGeometry =
            in.renderer && !in.optionsChanged && geometryKey == in.geometryKey;
        if (sameGeometry && fieldKey == in.fieldKey) return true;

        // The field: the array's values, one component or the magnitude (uvr's own rule).
        uvr::Field field;
        field.name = array->GetName() ? array->GetName() : "values";
        field.association = cellFlag ? uvr::Association::Cell : uvr::Association::Point;
        field.components = components;
        const vtkIdType tuples = array->GetNumberOfTuples();
        field.values.resize(std::size_t(tuples) * std::size_t(components));
        std::vector<double> tuple(static_cast<std::size_t>(components));
        for (vtkIdType i = 0; i < tuples; ++i) {
            array->GetTuple(i, tuple.data());
            for (int k = 0; k < components; ++k)
                field.values[std::size_t(i) * components + k] = float(tuple[std::size_t(k)]);
        }

        if (sameGeometry && in.association == field.association) {
            // A new time step or array on the same geometry: new values only.
            in.renderer->setFieldValues(uvr::scalarFieldOf(*in.mesh, field, component));
            in.fieldKey = fieldKey;
            return true;
        }
        in.renderer.reset();
        in.mesh = meshOf(grid);
        if (in.mesh->cellCount() == 0)
            throw uvr::Error(uvr::ErrorKind::Argument,
                             "the input has no volume cells (tetrahedra, hexahedra, wedges, "
                             "pyramids, polyhedra): nothing to render");
        const uvr::ScalarField scalars = uvr::scalarFieldOf(*in.mesh, field, component);
        uvr::ProgressFn report;
        if (progress) {
            report.step = [progress, client](const std::string& step) {
                progress(client, step.c_str(), 0.0);
            };
            report.fraction = [progress, client](double f) { progress(client, nullptr, f); };
        }
        in.renderer = std::make_unique<uvr::Renderer>(*in.mesh, scalars, in.options, report);
        in.geometryKey = geometryKey;
        in.fieldKey = fieldKey;
        in.association = field.association;
        in.optionsChanged = false;
        in.failedStamp = 0;
        return true;
    } catch (const std::exception& e) {
        in.renderer.reset();
        in.fieldKey.clear();
        in.failedStamp = stamp;
        in.report = nlohmann::json{{"error", e.what()}}.dump();
        vtkErrorMacro(<< "uvr Volume: " << e.what());
        return false;
    }
}

void vtkUvrVolumeMapper::Render(vtkRenderer* ren, vtkVolume* vol) {
    Internals& in = *internals_;
    auto* rw = vtkOpenGLRenderWindow::SafeDownCast(ren->GetRenderWindow());
    vtkDataSet* input = this->GetInput();
    if (!rw || !input || input->GetNumberOfCells() == 0) return;
    if (!this->Prepare(input, nullptr, nullptr)) return;
    try {
        int width = 0, height = 0, x0 = 0, y0 = 0;
        ren->GetTiledSizeAndOrigin(&width, &height, &x0, &y0);
        if (width < 1 || height < 1) return;

        // The frame's settings: the panel's, the view's camera and the representation's
        // transfer function, range and opacity unit distance.
        uvr::RenderSettings s = in.settings;
        s.width = width;
        s.height = height;
        vtkCamera* cam = ren->GetActiveCamera();
        s.camera = cameraOf(cam);
        vtkVolumeProperty* prop = vol->GetProperty();
        vtkColorTransferFunction* ctf = prop->GetRGBTransferFunction(0);
        vtkPiecewiseFunction* pwf = prop->GetScalarOpacity(0);
        double range[2];
        ctf->GetRange(range);
        const bool logScale = ctf->GetScale() == VTK_CTF_LOG10 && range[0] > 0.0;
        s.tf = tfOf(ctf, pwf, range, logScale);
        s.range = std::pair<float, float>(float(range[0]), float(range[1]));
        s.opacityUnit = float(prop->GetScalarOpacityUnitDistance(0));

        // Depth in: the opaque geometry drawn so far ends the rays. The window depth d of a
        // point at view depth z (along the view direction from the camera) between the clipping
        // planes n and f is, with w = 2d - 1, perspective: w = ((f + n) - 2fn / z) / (f - n),
        // parallel: w = (2z - (f + n)) / (f - n). The buffer's rows run from the bottom, the
        // library's from the top.
        std::vector<float> depth(std::size_t(width) * std::size_t(height));
        glReadPixels(x0, y0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
        const double* clip = cam->GetClippingRange();
        const double n = clip[0], f = clip[1];
        const bool parallel = cam->GetParallelProjection() != 0;
        s.depthIn.resize(depth.size());
        for (int y = 0; y < height; ++y) {
            for (int x = 0; x < width; ++x) {
                const double d = depth[std::size_t(y) * width + x];
                float& out = s.depthIn[std::size_t(height - 1 - y) * width + x];
                if (d >= 1.0) {
                    out = std::numeric_limits<float>::infinity();
                    continue;
                }
                const double w = 2.0 * d - 1.0;
                out = float(parallel ? ((f - n) * w + f + n) / 2.0
                                     : 2.0 * f * n / ((f + n) - w * (f - n)));
            }
        }

        uvr::RenderResult r = in.renderer->render(s);
        in.report = uvr::frameReport(*in.renderer, s, r).dump();

        // Composite the premultiplied frame over the framebuffer. It goes up as 8-bit RGBA,
        // what the framebuffer holds (a float texture is read as bytes in ParaView's GUI).
        in.upload.resize(std::size_t(width) * height * 4);
        for (int y = 0; y < height; ++y) {
            const uvr::Vec4f* row = &r.image.pixels[std::size_t(y) * width];
            unsigned char* out = &in.upload[std::size_t(height - 1 - y) * width * 4];
            for (int x = 0; x < width; ++x)
                for (int c = 0; c < 4; ++c) {
                    const float v = row[x][c];
                    out[4 * x + c] = static_cast<unsigned char>(v >= 1.f  ? 255.f
                                                                : v > 0.f ? v * 255.f + 0.5f
                                                                          : 0.f);
                }
        }
        in.texture->SetContext(rw);
        {
            // Qt's own uploads in ParaView's GUI can leave the unpack state set (rows or pixels
            // skipped): the upload then reads the wrong memory. Cleared here, restored after.
            const GLenum keys[] = {GL_UNPACK_ROW_LENGTH, GL_UNPACK_SKIP_ROWS, GL_UNPACK_SKIP_PIXELS,
                                   GL_UNPACK_IMAGE_HEIGHT, GL_UNPACK_SKIP_IMAGES};
            GLint saved[5];
            for (int i = 0; i < 5; ++i) {
                glGetIntegerv(keys[i], &saved[i]);
                glPixelStorei(keys[i], 0);
            }
            GLint unpackBuffer = 0;
            glGetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &unpackBuffer);
            glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
            in.texture->Create2DFromRaw(unsigned(width), unsigned(height), 4, VTK_UNSIGNED_CHAR,
                                        in.upload.data());
            glBindBuffer(GL_PIXEL_UNPACK_BUFFER, GLuint(unpackBuffer));
            for (int i = 0; i < 5; ++i) glPixelStorei(keys[i], saved[i]);
        }
        vtkOpenGLState* gl = rw->GetState();
        vtkOpenGLState::ScopedglEnableDisable blend(gl, GL_BLEND);
        vtkOpenGLState::ScopedglEnableDisable depthTest(gl, GL_DEPTH_TEST);
        vtkOpenGLState::ScopedglBlendFuncSeparate blendFunc(gl);
        vtkOpenGLState::ScopedglDepthMask depthMask(gl);
        gl->vtkglEnable(GL_BLEND);
        gl->vtkglDisable(GL_DEPTH_TEST);
        gl->vtkglDepthMask(GL_FALSE);
        gl->vtkglBlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
        // VTK's own full-screen pass (vtkTextureObject::CopyToFrameBuffer's quad drew one of
        // its two triangles from stale vertex data in ParaView's GUI).
        if (!in.quad)
            in.quad = std::make_unique<vtkOpenGLQuadHelper>(rw, nullptr, kBlitFragmentShader, "");
        else
            rw->GetShaderCache()->ReadyShaderProgram(in.quad->Program);
        if (!in.quad->Program) throw uvr::Error(uvr::ErrorKind::Internal, "the blit shader failed");
        in.texture->Activate();
        in.quad->Program->SetUniformi("source", in.texture->GetTextureUnit());
        in.quad->Render();
        in.texture->Deactivate();
        gl->vtkglPixelStorei(GL_UNPACK_ALIGNMENT, 4);  // Create2DFromRaw left 1
    } catch (const std::exception& e) {
        in.report = nlohmann::json{{"error", e.what()}}.dump();
        vtkErrorMacro(<< "uvr Volume: " << e.what());
    }
}

void vtkUvrVolumeMapper::ReleaseGraphicsResources(vtkWindow* window) {
    internals_->quad.reset();
    internals_->texture->ReleaseGraphicsResources(window);
}
