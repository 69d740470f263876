// SPDX-License-Identifier: MIT
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// First 8 bytes of a native uvr mesh file (.uvrm).
inline constexpr char kNativeMagic[8] = {'U', 'V', 'R', 'M', 'E', 'S', 'H', '\0'};

/// The counts, fields and cell types of a mesh file, known without reading its arrays.
struct MeshSummary {
    std::uint64_t pointCount = 0, cellCount = 0, fileBytes = 0;
    std::map<CellType, std::uint64_t> cellTypes;
    std::vector<FieldInfo> fields;
};

/// Reads a native uvr mesh (.uvrm, documented in docs/NATIVE_FORMAT.md); all counts are checked
/// against the file size before anything is allocated.
Mesh readNative(const std::string& path, const ReadOptions& options = {});

/// What `uvr info` prints of a .uvrm without reading its arrays: the header's counts and fields
/// and, with cellTypes, the cell types (one byte per cell, read in chunks); checked as
/// readNative checks them.
MeshSummary readNativeSummary(const std::string& path, bool cellTypes = true);

/// Writes a mesh in the native format, atomically (temporary file, then rename).
void writeNative(const Mesh& mesh, const std::string& path,
                 const std::function<void(double)>& progress = {});

}  // namespace uvr
