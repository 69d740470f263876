// SPDX-License-Identifier: MIT
// Prepared caches (issue 16): a prepared mesh written to a flat, checked binary file so that a
// later render reads it and uploads it instead of reading the mesh and preparing it again.
// docs/PREPARED_CACHE.md describes the format.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "uvr/core/bounds.h"
#include "uvr/core/error.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/load_budget.h"
#include "uvr/prepare/prepared_mesh.h"

namespace uvr {

/// First 8 bytes of a prepared cache file.
inline constexpr char kPreparedCacheMagic[8] = {'U', 'V', 'R', 'P', 'R', 'E', 'P', '\0'};
/// The format version this uvr writes and reads (any other is refused).
inline constexpr std::uint32_t kPreparedCacheVersion = 3;
/// The default cache of a mesh file: MESH + this suffix.
inline constexpr const char* kPreparedCacheSuffix = ".uvrprep";

/// What a prepared cache was made from: the source file (canonical path, size, modification time,
/// a fingerprint of its first and last MiB), the field and time step asked for, and the
/// preparation options that change the result. A cache is used only for an equal key.
struct CacheKey {
    std::string sourcePath;          ///< canonical path of the mesh file
    std::uint64_t sourceSize = 0;    ///< bytes
    std::int64_t sourceMtimeNs = 0;  ///< modification time, ns since the epoch
    std::uint64_t fingerprint = 0;   ///< CRC32 of the first MiB (high half) and last MiB (low)
    std::string fieldSpec;           ///< --field as given ("" for the default field)
    std::string step;                ///< the time step asked for ("" for the first)
    bool splitCells = false;         ///< PrepareOptions::cells.splitCells
    bool partitions = true;          ///< PrepareOptions::partitions
    bool meshBvh = true;             ///< PrepareOptions::meshBvh
    bool forAuto = false;            ///< PrepareOptions::forAuto (and autoOnGpu below)
    bool autoOnGpu = false;          ///< PrepareOptions::autoOnGpu, with forAuto
    bool seedGrids = true;           ///< PrepareOptions::seedGrids
    bool macroGrids = true;          ///< PrepareOptions::macroGrids
    std::uint32_t leafCells = 0;     ///< PrepareOptions::kd.leafCells
};

/// The key of a preparation of `meshPath` (stat and 2 MiB read: cheap) with `options`, for the
/// field and step the caller asked for. Throws Error(Io) when the file cannot be read.
CacheKey makeCacheKey(const std::string& meshPath, const std::string& fieldSpec,
                      const std::string& step, const PrepareOptions& options);

/// Why a cache of key `stored` must not be used where `expected` is asked for, one sentence
/// ("the mesh changed since the cache was prepared: ..."); empty when the keys are equal.
std::string cacheKeyMismatch(const CacheKey& stored, const CacheKey& expected);

/// What rendering needs to know of the source mesh without reading it: its counts, the bounds
/// of its rendered cells in its file's coordinates (ValidationReport::bounds: the camera's
/// reset), the field chosen, and the lines a load and check of it printed.
struct SourceSummary {
    std::uint64_t points = 0;
    std::uint64_t cells = 0;
    Bounds3f bounds;  ///< ValidationReport::bounds (file coordinates)
    std::string fieldName;
    Association association = Association::Point;
    std::string fieldChoice;            ///< ScalarField::choice
    std::vector<std::string> notes;     ///< the reader's notes (Mesh::notes)
    std::vector<std::string> findings;  ///< ValidationReport::findings()

    /// The field as a ScalarField without values (for describe() and the statistics).
    ScalarField field() const { return {fieldName, association, {}, fieldChoice}; }
};

/// A cache whose key does not match what is asked for (a stale or foreign cache): reason() says
/// why. Its kind is ErrorKind::Argument.
class StaleCacheError : public Error {
public:
    /// "FILE: the prepared cache does not match: REASON".
    StaleCacheError(const std::string& file, const std::string& reason);
    /// The mismatch alone (cacheKeyMismatch).
    const std::string& reason() const { return reason_; }

private:
    std::string reason_;
};

/// The header of a prepared cache: its key and the source's summary, read without the arrays.
struct CacheHeader {
    CacheKey key;
    SourceSummary source;
    std::uint64_t cells = 0;       ///< rendered cells (tetrahedra and native cells)
    std::uint64_t arrayBytes = 0;  ///< bytes of the arrays
    std::string builderDevice;     ///< where the BVHs and k-d tree were built ("cpu", "the GPU")
};

/// Writes `mesh` (as prepareMesh made it) with its key and source summary to `path` through a
/// temporary renamed on success (core/output_file.h): only what rendering reads (the arrays of
/// PreparedMesh::kernelMesh, the compact neighbours, BVHs, partitions, seed and macrocell
/// grids), not the arrays that only building and updateFieldValues use. progress hears the
/// fraction of bytes written. Returns the bytes written.
std::uint64_t writePreparedCache(const PreparedMesh& mesh, const CacheKey& key,
                                 const SourceSummary& source, const std::string& path,
                                 const std::function<void(double)>& progress = {});

/// Reads the header of a prepared cache (magic, version, header checksum); throws Error(Parse)
/// naming the file and what is wrong, Error(Io) when it cannot be read.
CacheHeader readPreparedCacheHeader(const std::string& path);

/// Reads a prepared cache written for `expected`: StaleCacheError when its key differs; else
/// every array, each count and offset checked against the file size, each charged to `budget`
/// before it is allocated and its CRC32 verified (Error(Parse) naming the file and the array).
/// The result renders like the mesh it was written from (bit for bit) and has cacheFile set:
/// updateFieldValues refuses it. header, when given, receives the header.
PreparedMesh readPreparedCache(const std::string& path, const CacheKey& expected,
                               LoadBudget& budget, CacheHeader* header = nullptr,
                               const std::function<void(double)>& progress = {});

}  // namespace uvr
