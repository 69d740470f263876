// SPDX-License-Identifier: MIT
// VTKHDF (.vtkhdf, .hdf): VTK's HDF5-based format, UnstructuredGrid type, through the HDF5 C
// library (optional: without it every call throws Error(Unsupported) saying what to install).
// Several partitions are merged into one mesh; the temporal layout (/VTKHDF/Steps, version 2)
// gives a MeshSeries whose steps may share their geometry and differ only in field values.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/read_options.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// True when this uvr was built with HDF5 (VTKHDF can be read and written).
bool vtkHdfSupported();

/// True when path names a VTKHDF file by its extension (.vtkhdf, .hdf), or starts with the HDF5
/// signature and holds a /VTKHDF group (so that other HDF5 files, such as netCDF-4 Exodus
/// files, are left to their readers). Never throws for unreadable files: it answers false.
bool looksLikeVtkHdf(const std::string& path);

/// Opens a VTKHDF UnstructuredGrid file as a series: the steps of /VTKHDF/Steps (times from
/// Steps/Values), or one step at time 0. Reads only the step table; throws Error naming the file
/// and the dataset (not HDF5, no /VTKHDF, another Type, a missing or inconsistent dataset).
std::unique_ptr<MeshSeries> openVtkHdfSeries(const std::string& path,
                                             const ReadOptions& options = {});

/// Reads the first step of a VTKHDF file: its partitions merged, cells converted as in .vtu
/// (corners of quadratic cells, voxels as hexahedra, 0D-2D cells dropped with a note).
Mesh readVtkHdf(const std::string& path, const ReadOptions& options = {});
/// How many partitions step `step` of a VTKHDF file has (only the step table is read).
std::size_t vtkHdfPartitionCount(const std::string& path, std::size_t step = 0);
/// Reads the partitions [first, end) of step `step` as readVtkHdf reads them all (a
/// data-parallel rank's part): their points and cells, with ids in the whole file's order
/// (kPieceIdShift). Throws Error(Argument) for an empty range or one beyond the step's
/// partitions.
MeshPart readVtkHdfPart(const std::string& path, std::size_t first, std::size_t end,
                        const ReadOptions& options = {}, std::size_t step = 0);

/// Writes a mesh as VTKHDF version 2.2, one partition, no time steps: float32 points, int64
/// offsets and connectivity, uint8 types, float32 fields (N or N x components). Written
/// atomically (built in memory, then a temporary file renamed over path); throws
/// Error(Argument) for field names HDF5 cannot hold ('/' or empty) or repeated.
void writeVtkHdf(const Mesh& mesh, const std::string& path,
                 const std::function<void(double)>& progress = {});

/// Writes a time series of one geometry as a temporal VTKHDF file (version 2.2, one partition):
/// the points and cells stored once (every step's geometry offsets 0), each field one dataset
/// holding every step's values in turn with Steps/PointDataOffsets or CellDataOffsets. mesh gives
/// the geometry and the fields' names, associations and components (its own values are not
/// written); stepFields(k) gives step k's fields, which must match them. Written atomically;
/// throws Error(Argument) for mismatched or unnamable fields, or no steps.
void writeVtkHdfSeries(const Mesh& mesh, const std::vector<double>& times,
                       const std::function<std::vector<Field>(std::size_t)>& stepFields,
                       const std::string& path, const std::function<void(double)>& progress = {});

}  // namespace uvr
