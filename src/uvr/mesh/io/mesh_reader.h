// SPDX-License-Identifier: MIT
#pragma once

#include <string>

#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// Reads any supported mesh file (.vtk legacy, .vtu, .pvtu, .uvrm native), chosen by magic
/// bytes first and extension second; throws Error naming the file on failure.
Mesh readMesh(const std::string& path, const ReadOptions& options = {});

/// Writes a mesh in the format its extension names (.uvrm native or .vtu); throws
/// Error(Argument) for other extensions. The file is written atomically.
void writeMesh(const Mesh& mesh, const std::string& path);
/// Throws Error(Argument) naming path unless writeMesh can write its format (.uvrm or .vtu):
/// commands call it before any heavy work.
void checkMeshWritable(const std::string& path);

}  // namespace uvr
