// SPDX-License-Identifier: MIT
// Exodus II files (.e, .exo, .ex2, .g), read through Debian's netCDF C library: the volume
// element blocks (tetrahedra, hexahedra, wedges, pyramids; higher-order ones through their
// corners), nodal and element variables as point and cell fields, every time step.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// True when uvr was built with netCDF (libnetcdf-dev) and so reads Exodus II files.
bool exodusSupported();

/// True when a file's first bytes are a netCDF ("CDF\x01", "CDF\x02", "CDF\x05") or HDF5
/// signature and its extension is an Exodus II one (.e, .exo, .ex2, .exii, .g, .gen).
bool looksLikeExodus(std::string_view head, const std::string& path);

/// Opens an Exodus II file as a series of its time steps (`time_whole`; a file without steps is
/// one step at time 0). Reads the metadata only; each step's geometry and variables are read by
/// readStep, only the variables by readFieldsIfSameGeometry. Throws Error naming the file and
/// the variable or block (Error(Unsupported) when uvr was built without netCDF).
std::unique_ptr<MeshSeries> openExodus(const std::string& path, const ReadOptions& options = {});

/// The first time step of an Exodus II file (openExodus(path)->readStep(0)).
Mesh readExodus(const std::string& path, const ReadOptions& options = {});

/// Cells of an Exodus II file's mesh: its volumetric blocks' elements (the metadata only).
std::uint64_t exodusCellCount(const std::string& path);

/// The cells [first, end) of step `step` (blocks in file order) and what they use, as meshPart
/// takes them from the whole step (a data-parallel rank's part): each block's connectivity read
/// over those cells' rows only, the coordinates and nodal variables over the span of the node
/// numbers they use. Throws Error(Argument) for a range beyond the file's cells.
MeshPart readExodusPart(const std::string& path, std::uint64_t first, std::uint64_t end,
                        const ReadOptions& options = {}, std::size_t step = 0);

}  // namespace uvr
