// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/mesh_reader.h"

#include <cstring>
#include <filesystem>
#include <fstream>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/io/exodus.h"
#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/io/vtk_compression.h"
#include "uvr/mesh/io/vtk_legacy.h"
#include "uvr/mesh/io/vtkhdf.h"
#include "uvr/mesh/io/vtu.h"

namespace uvr {

MeshFormat sniffMeshFormat(const std::string& path) {
    using Format = MeshFormat;
    checkRegularFile(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throwError(ErrorKind::Io, path, std::string("cannot open: ") + std::strerror(errno));
    char head[512] = {};
    in.read(head, sizeof(head) - 1);
    const std::string text(head, static_cast<size_t>(in.gcount()));
    if (text.size() >= 8 && std::memcmp(text.data(), kNativeMagic, 8) == 0) return Format::Native;
    if (looksLikeExodus(text, path)) return Format::Exodus;
    if (text.rfind("# vtk DataFile", 0) == 0) return Format::Legacy;
    if (text.find("PUnstructuredGrid") != std::string::npos) return Format::Pvtu;
    if (text.find("<VTKFile") != std::string::npos &&
        text.find("type=\"Collection\"") != std::string::npos)
        return Format::Pvd;
    if (text.find("<VTKFile") != std::string::npos) return Format::Vtu;
    // VTKHDF: an .vtkhdf/.hdf name, or HDF5 with a /VTKHDF group (netCDF-4 files are HDF5 too).
    if (looksLikeVtkHdf(path)) return Format::VtkHdf;
    const std::string ext = fileExtension(path);
    if (ext == ".vtk") return Format::Legacy;
    if (ext == ".vtu") return Format::Vtu;
    if (ext == ".pvtu") return Format::Pvtu;
    if (ext == ".pvd") return Format::Pvd;
    if (ext == ".uvrm") return Format::Native;
    return Format::Unknown;
}

bool sameFile(const std::string& a, const std::string& b) {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::exists(a, ec) && fs::exists(b, ec)) {
        const bool same = fs::equivalent(a, b, ec);
        if (!ec) return same;
    }
    const fs::path ca = fs::weakly_canonical(a, ec);
    if (ec) return fs::path(a).lexically_normal() == fs::path(b).lexically_normal();
    const fs::path cb = fs::weakly_canonical(b, ec);
    return !ec && ca == cb;
}

Mesh readMesh(const std::string& path, const ReadOptions& options) {
    using Format = MeshFormat;
    switch (sniffMeshFormat(path)) {
        case Format::Legacy:
            return readVtkLegacy(path, options);
        case Format::Vtu:
            return readVtu(path, options);
        case Format::Pvtu:
            return readPvtu(path, options);
        case Format::Pvd:  // its first time step
            return openMeshSeries(path, options)->readStep(0);
        case Format::Native:
            return readNative(path, options);
        case Format::Exodus:  // its first time step
            return readExodus(path, options);
        case Format::VtkHdf:
            return readVtkHdf(path, options);
        case Format::Unknown:
            break;
    }
    throwError(ErrorKind::Parse, path,
               "unrecognised file format: expected a legacy VTK file ('# vtk DataFile' header), "
               "VTK XML (.vtu/.pvtu), a ParaView collection (.pvd), Exodus II (.e/.exo/.ex2/.g), "
               "VTKHDF (.vtkhdf/.hdf) or a native uvr mesh (.uvrm)");
}

std::optional<MeshSummary> readMeshSummary(const std::string& path, bool cellTypes) {
    if (sniffMeshFormat(path) == MeshFormat::Native) return readNativeSummary(path, cellTypes);
    return std::nullopt;
}

void checkMeshWritable(const std::string& path, const MeshWriteOptions& options) {
    const std::string ext = fileExtension(path);
    if (ext != ".uvrm" && ext != ".vtu" && ext != ".vtk" && ext != ".vtkhdf")
        throwError(ErrorKind::Argument, path,
                   "cannot write this format: the output name must end in .uvrm (native), .vtu, "
                   ".vtk (legacy) or .vtkhdf");
    if (ext == ".vtkhdf" && !vtkHdfSupported())
        throwError(ErrorKind::Unsupported, path,
                   "this uvr was built without HDF5, which VTKHDF files need: install "
                   "libhdf5-dev and rebuild");
    if (options.compressor && ext != ".vtu")
        throwError(ErrorKind::Argument, path,
                   "a compressor applies to .vtu output only, not to " + ext);
    if (options.compressor) requireVtuCompressor(*options.compressor, path);
}

void writeMesh(const Mesh& mesh, const std::string& path,
               const std::function<void(double)>& progress, const MeshWriteOptions& options) {
    checkMeshWritable(path, options);
    const std::string ext = fileExtension(path);
    if (ext == ".uvrm") return writeNative(mesh, path, progress);
    if (ext == ".vtk") return writeVtkLegacy(mesh, path, progress);
    if (ext == ".vtkhdf") return writeVtkHdf(mesh, path, progress);
    VtuWriteOptions vtu;
    if (options.compressor) vtu.compressor = *options.compressor;
    writeVtu(mesh, path, progress, vtu);
}

}  // namespace uvr
