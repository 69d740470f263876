// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/hdf5_structure.h"

#include "uvr/core/error.h"

#ifdef UVR_HAS_HDF5
#include <hdf5.h>

#include <cstring>
#include <limits>
#endif

namespace uvr {

void expectStored(const std::string& file, const std::string& what, const Hdf5DatasetInfo& d) {
    const long double stored =
        static_cast<long double>(d.storageBytes) * (d.filtered ? kMaxHdf5FilterRatio : 1);
    if (static_cast<long double>(d.declaredBytes) <= stored) return;
    throwError(ErrorKind::Parse, file,
               what + " declares " + std::to_string(d.declaredBytes) +
                   " bytes, but the file stores only " + std::to_string(d.storageBytes) +
                   " bytes of it" + (d.filtered ? " (compressed)" : ""));
}

#ifndef UVR_HAS_HDF5

bool hdf5WalkSupported() {
    return false;
}

std::vector<Hdf5DatasetInfo> walkHdf5Structure(const std::string& path) {
    throwError(ErrorKind::Unsupported, path, "this uvr was built without HDF5");
}

#else

namespace {

/// An HDF5 identifier closed when it goes out of scope.
struct Handle {
    hid_t id;
    herr_t (*close)(hid_t);
    ~Handle() {
        if (id >= 0) close(id);
    }
};

/// The walk's state: what it found, and the first refusal (HDF5 calls the callback from C, so
/// errors are kept here and thrown after the walk).
struct Walk {
    std::string path;
    std::vector<Hdf5DatasetInfo> datasets;
    ErrorKind kind = ErrorKind::Parse;
    std::string error;

    int fail(ErrorKind k, const std::string& message) {
        kind = k;
        error = message;
        return -1;
    }
};

/// "'/name' links to OBJECT in FILE" of an external link (its value unpacked).
std::string externalTarget(hid_t group, const char* name, std::size_t size) {
    if (size == 0 || size > (1u << 16)) return "an unreadable target";
    std::vector<char> value(size);
    if (H5Lget_val(group, name, value.data(), size, H5P_DEFAULT) < 0) return "an unreadable target";
    unsigned flags = 0;
    const char* file = nullptr;
    const char* object = nullptr;
    if (H5Lunpack_elink_val(value.data(), size, &flags, &file, &object) < 0 || !file || !object)
        return "an unreadable target";
    return "object '" + std::string(object, strnlen(object, 4096)) + "' of the file '" +
           std::string(file, strnlen(file, 4096)) + "'";
}

/// Checks one dataset's layout and storage, walks its chunk index, records what it declares.
int visitDataset(Walk& walk, hid_t group, const char* name) {
    const std::string where = std::string("/") + name;
    Handle d{H5Dopen2(group, name, H5P_DEFAULT), H5Dclose};
    if (d.id < 0) return walk.fail(ErrorKind::Parse, where + ": could not open the dataset");
    Handle dcpl{H5Dget_create_plist(d.id), H5Pclose};
    if (dcpl.id < 0)
        return walk.fail(ErrorKind::Parse, where + ": could not read the creation properties");
    const H5D_layout_t layout = H5Pget_layout(dcpl.id);
    if (layout == H5D_VIRTUAL)
        return walk.fail(ErrorKind::Unsupported,
                         where +
                             ": a virtual dataset (its data lie in other files); uvr reads "
                             "no data from other files");
    if (const int external = H5Pget_external_count(dcpl.id); external != 0) {
        char file[1024] = {};
        off_t offset = 0;
        hsize_t size = 0;
        std::string target = "other files";
        if (external > 0 && H5Pget_external(dcpl.id, 0, sizeof file - 1, file, &offset, &size) >= 0)
            target = "the file '" + std::string(file, strnlen(file, sizeof file)) + "'";
        return walk.fail(ErrorKind::Unsupported, where + ": a dataset stored externally, in " +
                                                     target +
                                                     "; uvr reads no data from other files");
    }
    Handle space{H5Dget_space(d.id), H5Sclose};
    Handle type{H5Dget_type(d.id), H5Tclose};
    if (space.id < 0 || type.id < 0)
        return walk.fail(ErrorKind::Parse, where + ": could not read the dataspace or type");
    const hssize_t points = H5Sget_simple_extent_npoints(space.id);
    const std::size_t typeBytes = H5Tget_size(type.id);
    if (points < 0 || typeBytes == 0)
        return walk.fail(ErrorKind::Parse, where + ": could not read the dataspace or type");
    if (layout == H5D_CHUNKED) {
        // Counting the chunks walks the whole chunk index (the B-tree reads descend).
        hsize_t chunks = 0;
        if (H5Dget_num_chunks(d.id, space.id, &chunks) < 0)
            return walk.fail(ErrorKind::Parse, where + ": could not read the chunk index");
    }
    Hdf5DatasetInfo info;
    info.name = name;
    const long double declared = static_cast<long double>(points) * typeBytes;
    info.declaredBytes = declared > 1.8e19L ? std::numeric_limits<std::uint64_t>::max()
                                            : static_cast<std::uint64_t>(declared);
    info.storageBytes = H5Dget_storage_size(d.id);
    info.filtered = H5Pget_nfilters(dcpl.id) > 0;
    walk.datasets.push_back(std::move(info));
    return 0;
}

herr_t visitLink(hid_t group, const char* name, const H5L_info_t* link, void* data) {
    Walk& walk = *static_cast<Walk*>(data);
    const std::string where = std::string("/") + name;
    if (link->type == H5L_TYPE_EXTERNAL)
        return walk.fail(ErrorKind::Unsupported,
                         "the external link '" + where + "' to " +
                             externalTarget(group, name, link->u.val_size) +
                             ": uvr does not follow links into other files");
    if (link->type != H5L_TYPE_HARD && link->type != H5L_TYPE_SOFT)
        return walk.fail(ErrorKind::Unsupported, "the user-defined link '" + where + "' (type " +
                                                     std::to_string(int(link->type)) +
                                                     "): uvr does not follow it");
    if (link->type == H5L_TYPE_SOFT) return 0;  // a path within this file, checked where it leads
    H5O_info_t object;
    if (H5Oget_info_by_name2(group, name, &object, H5O_INFO_BASIC, H5P_DEFAULT) < 0)
        return walk.fail(ErrorKind::Parse, where + ": could not read the object");
    if (object.type == H5O_TYPE_DATASET) return visitDataset(walk, group, name);
    return 0;
}

}  // namespace

bool hdf5WalkSupported() {
    return true;
}

std::vector<Hdf5DatasetInfo> walkHdf5Structure(const std::string& path) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    Handle file{H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
    if (file.id < 0) {
        H5Eclear2(H5E_DEFAULT);
        throwError(ErrorKind::Parse, path, "HDF5 could not open the file");
    }
    Walk walk;
    walk.path = path;
    const herr_t status = H5Lvisit(file.id, H5_INDEX_NAME, H5_ITER_NATIVE, visitLink, &walk);
    H5Eclear2(H5E_DEFAULT);
    if (!walk.error.empty()) throwError(walk.kind, path, walk.error);
    if (status < 0) throwError(ErrorKind::Parse, path, "HDF5 could not list the file's links");
    return walk.datasets;
}

#endif

}  // namespace uvr
