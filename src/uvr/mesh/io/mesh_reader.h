// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>

#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/io/vtu.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// The formats readMesh reads.
enum class MeshFormat { Legacy, Vtu, Pvtu, Pvd, Native, Exodus, VtkHdf, Unknown };

/// The format of a file as readMesh and openMeshSeries choose it: magic bytes and content first
/// (a VTKFile of type Collection is a .pvd whatever its name), extension second; Error(Io) when
/// it cannot be opened.
MeshFormat sniffMeshFormat(const std::string& path);

/// True when a and b name one file: the same inode when both exist (hard and symbolic links
/// included), else the same weakly canonical path (`./x`, `sub/../x` and `x` alike).
bool sameFile(const std::string& a, const std::string& b);

/// Reads any supported mesh file (.vtk legacy, .vtu, .pvtu, .pvd, Exodus II and VTKHDF: their
/// first step, .uvrm native), chosen by magic bytes first and extension second; throws Error
/// naming the file on failure.
Mesh readMesh(const std::string& path, const ReadOptions& options = {});

/// The counts, cell types and fields of a file whose format has a header that holds them (.uvrm),
/// without reading its arrays (the cell types, one byte per cell, only with cellTypes); empty for
/// formats that must be read whole to know them.
std::optional<MeshSummary> readMeshSummary(const std::string& path, bool cellTypes = true);

/// How writeMesh writes: the .vtu compressor (unset: zlib; only .vtu outputs take one).
struct MeshWriteOptions {
    std::optional<VtuCompressor> compressor;
};

/// Writes a mesh in the format its extension names (.uvrm native, .vtu, .vtk legacy binary or
/// .vtkhdf), reporting the fraction of bytes written to progress (when given) as it goes; throws
/// Error(Argument) for other extensions. The file is written atomically.
void writeMesh(const Mesh& mesh, const std::string& path,
               const std::function<void(double)>& progress = {},
               const MeshWriteOptions& options = {});
/// Throws Error(Argument) naming path unless writeMesh can write its format (.uvrm, .vtu, .vtk or
/// .vtkhdf; Error(Unsupported) for .vtkhdf in a build without HDF5) with these options: commands
/// call it before any heavy work.
void checkMeshWritable(const std::string& path, const MeshWriteOptions& options = {});

}  // namespace uvr
