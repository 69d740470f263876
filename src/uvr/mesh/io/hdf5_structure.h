// SPDX-License-Identifier: MIT
// A walk over an HDF5 file's whole structure (VTKHDF files, netCDF-4 Exodus files) that refuses
// what would make HDF5 read other files, and reports what each dataset declares and stores.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace uvr {

/// The most a filtered (compressed) HDF5 dataset may declare per stored byte: deflate cannot
/// expand data by more than 1032:1, so a dataset declaring more is refused before anything is
/// allocated (its declared bytes are then charged to the load's budget as they are read).
constexpr std::uint64_t kMaxHdf5FilterRatio = 1032;

/// What the walk found of one dataset.
struct Hdf5DatasetInfo {
    std::string name;                 ///< its path from the root, without the leading '/'
    std::uint64_t declaredBytes = 0;  ///< elements times the stored type's size
    std::uint64_t storageBytes = 0;   ///< bytes the file allocates for it (H5Dget_storage_size)
    bool filtered = false;            ///< compressed or otherwise filtered
};

/// Error(Parse) "FILE: WHAT declares N bytes, but the file stores only M bytes" unless the
/// dataset's declared bytes fit its storage (times kMaxHdf5FilterRatio when filtered).
void expectStored(const std::string& file, const std::string& what, const Hdf5DatasetInfo& d);

/// True when this uvr can walk HDF5 files (built with HDF5).
bool hdf5WalkSupported();

/// Visits every link of an HDF5 file reachable from its root through hard links, and every
/// dataset's creation properties and chunk index (the B-tree a read would walk). Throws
/// Error(Unsupported) naming the file, the link and its target for an external or user-defined
/// link, and naming the dataset for external storage (H5Pget_external_count) or a virtual
/// dataset: uvr reads no data from other files. Error(Parse) when HDF5 fails to read the
/// structure. The caller holds FormatLibraryLock; HDF5 failures are not printed.
std::vector<Hdf5DatasetInfo> walkHdf5Structure(const std::string& path);

}  // namespace uvr
