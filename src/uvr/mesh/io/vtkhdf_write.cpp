// SPDX-License-Identifier: MIT
// The VTKHDF UnstructuredGrid writer (docs/FORMATS.md, section VTKHDF): one mesh, or a time
// series of its fields (a Steps group); the reader is vtkhdf.cpp, which also holds both's
// stand-ins for a build without HDF5.
#include <cstring>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/mesh/io/vtkhdf.h"

#ifdef UVR_HAS_HDF5
#include <hdf5.h>

#include "uvr/core/output_file.h"
#include "uvr/mesh/io/hdf5_handle.h"
#include "uvr/mesh/io/isolated_probe.h"
#include "uvr/mesh/io/vtk_cells.h"
#include "uvr/mesh/validate.h"
#endif

namespace uvr {

#ifdef UVR_HAS_HDF5

namespace {

/// A name HDF5 can hold as a link ('/' separates groups; "." is the group itself).
void checkFieldNames(const Mesh& mesh, const std::string& path) {
    std::set<std::pair<Association, std::string> > seen;
    for (const Field& f : mesh.fields) {
        if (f.name.empty() || f.name == "." || f.name.find('/') != std::string::npos)
            throwError(ErrorKind::Argument, path,
                       std::string(associationName(f.association)) + " field '" + f.name +
                           "': VTKHDF (HDF5) cannot name a dataset so (empty, '.' or with '/')");
        if (!seen.emplace(f.association, f.name).second)
            throwError(ErrorKind::Argument, path,
                       "two " + std::string(associationName(f.association)) + " fields named '" +
                           f.name + "': VTKHDF holds one dataset per name");
    }
}

/// Writes HDF5 objects into an in-memory file and checks every call (Error(Io) naming path).
class Hdf5Writer {
public:
    Hdf5Writer(const std::string& path, std::uint64_t sizeHint) : path_(path) {
        quietHdf5();
        H5Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
        ok(fapl.get(), "make file access properties");
        // The core driver without a backing store: the file lives in memory until its image is
        // written through OutputFile (atomic rename, devices, standard output).
        const std::size_t increment =
            static_cast<std::size_t>(std::clamp<std::uint64_t>(sizeHint, 1u << 20, 1u << 30));
        ok(H5Pset_fapl_core(fapl.get(), increment, false), "choose the in-memory driver");
        static std::atomic<unsigned> counter{0};
        const std::string name = "uvr-vtkhdf-" + std::to_string(counter++) + ".h5";
        file_ = H5Handle(H5Fcreate(name.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose);
        ok(file_.get(), "create the in-memory file");
    }

    hid_t file() const { return file_.get(); }

    template <typename T>
    T ok(T status, const std::string& what) const {
        if (status < 0) throwError(ErrorKind::Io, path_, "could not " + what + hdf5Message());
        return status;
    }

    /// A group that remembers the order of its members (the fields' order is kept).
    H5Handle group(hid_t parent, const char* name) const {
        H5Handle gcpl(H5Pcreate(H5P_GROUP_CREATE), H5Pclose);
        ok(gcpl.get(), "make group properties");
        ok(H5Pset_link_creation_order(gcpl.get(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED),
           "track the order of group members");
        H5Handle g(H5Gcreate2(parent, name, H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose);
        ok(g.get(), std::string("create group ") + name);
        return g;
    }

    /// A dataset of rows x columns (columns 0: one dimension) in fileType from memory values of
    /// memType.
    void dataset(hid_t parent, const std::string& name, hid_t fileType, hid_t memType,
                 std::uint64_t rows, std::uint64_t columns, const void* data) const {
        const hsize_t dims[2] = {rows, columns};
        H5Handle space(H5Screate_simple(columns ? 2 : 1, dims, nullptr), H5Sclose);
        ok(space.get(), "make the dataspace of " + name);
        H5Handle d(H5Dcreate2(parent, name.c_str(), fileType, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                              H5P_DEFAULT),
                   H5Dclose);
        ok(d.get(), "create dataset " + name);
        if (rows > 0)
            ok(H5Dwrite(d.get(), memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
               "write dataset " + name);
    }

    /// The whole file's bytes; the file is closed afterwards.
    std::vector<char> image() {
        ok(H5Fflush(file_.get(), H5F_SCOPE_GLOBAL), "flush the in-memory file");
        const ssize_t size = ok(H5Fget_file_image(file_.get(), nullptr, 0), "size the file image");
        std::vector<char> bytes(static_cast<std::size_t>(size));
        ok(H5Fget_file_image(file_.get(), bytes.data(), bytes.size()), "copy the file image");
        file_.reset();
        return bytes;
    }

private:
    std::string path_;
    H5Handle file_;
};

/// Writes the file of writeVtkHdf (times null: no steps, the mesh's fields) or of
/// writeVtkHdfSeries (every step's fields after one another, a Steps group).
void writeVtkHdfFile(const Mesh& mesh, const std::string& path,
                     const std::function<void(double)>& progress, const std::vector<double>* times,
                     const std::function<std::vector<Field>(std::size_t)>& stepFields) {
    validateStructure(mesh, path);
    checkFieldNames(mesh, path);
    const std::uint64_t steps = times ? times->size() : 1;
    if (steps == 0) throwError(ErrorKind::Argument, path, "a time series needs a time step");
    const std::uint64_t n = mesh.pointCount(), cells = mesh.cellCount();
    const std::uint64_t ids = mesh.cellIndices.size();
    std::uint64_t total = n * 12 + cells * 9 + 8 + ids * 8;
    for (const Field& f : mesh.fields) total += f.values.size() * 4 * steps;
    auto report = [&](std::uint64_t done) {
        if (progress) progress(0.5 * double(done) / double(std::max<std::uint64_t>(total, 1)));
    };

    // The file, in memory: /VTKHDF with Version and Type, one partition. The oldest version
    // that holds the data, so that older readers take it without a warning (VTK 9.1 reads 1.0):
    // 1.0 for one step, 2.0 (Steps) for a series.
    std::optional<FormatLibraryLock> lock(std::in_place);
    Hdf5Writer w(path, total + (1u << 16));
    H5Handle root = w.group(w.file(), "VTKHDF");
    {
        const std::int64_t version[2] = {times ? 2 : 1, 0};
        const hsize_t two = 2;
        H5Handle space(H5Screate_simple(1, &two, nullptr), H5Sclose);
        H5Handle attr(
            H5Acreate2(root.get(), "Version", H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
            H5Aclose);
        w.ok(attr.get(), "create attribute Version");
        w.ok(H5Awrite(attr.get(), H5T_NATIVE_INT64, version), "write attribute Version");
        const std::string type = "UnstructuredGrid";
        H5Handle str(H5Tcopy(H5T_C_S1), H5Tclose);
        w.ok(H5Tset_size(str.get(), type.size()), "make a string type");
        w.ok(H5Tset_strpad(str.get(), H5T_STR_NULLPAD), "make a string type");
        H5Handle scalar(H5Screate(H5S_SCALAR), H5Sclose);
        H5Handle typeAttr(
            H5Acreate2(root.get(), "Type", str.get(), scalar.get(), H5P_DEFAULT, H5P_DEFAULT),
            H5Aclose);
        w.ok(typeAttr.get(), "create attribute Type");
        w.ok(H5Awrite(typeAttr.get(), str.get(), type.data()), "write attribute Type");
    }
    const std::int64_t counts[3] = {static_cast<std::int64_t>(n), static_cast<std::int64_t>(cells),
                                    static_cast<std::int64_t>(ids)};
    w.dataset(root.get(), "NumberOfPoints", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, 0, &counts[0]);
    w.dataset(root.get(), "NumberOfCells", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, 0, &counts[1]);
    w.dataset(root.get(), "NumberOfConnectivityIds", H5T_STD_I64LE, H5T_NATIVE_INT64, 1, 0,
              &counts[2]);
    std::uint64_t done = 0;
    w.dataset(root.get(), "Points", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, n, 3, mesh.points.data());
    report(done += n * 12);
    // HDF5 converts the uint64 offsets and uint32 ids to int64 as it writes.
    w.dataset(root.get(), "Offsets", H5T_STD_I64LE, H5T_NATIVE_UINT64, cells + 1, 0,
              mesh.cellOffsets.data());
    w.dataset(root.get(), "Types", H5T_STD_U8LE, H5T_NATIVE_UINT8, cells, 0, mesh.cellTypes.data());
    report(done += cells * 9 + 8);
    w.dataset(root.get(), "Connectivity", H5T_STD_I64LE, H5T_NATIVE_UINT32, ids, 0,
              mesh.cellIndices.data());
    report(done += ids * 8);

    // Fields: one dataset each, every step's rows after one another.
    std::vector<H5Handle> datasets;
    for (Association association : {Association::Point, Association::Cell}) {
        H5Handle group =
            w.group(root.get(), association == Association::Point ? "PointData" : "CellData");
        for (const Field& f : mesh.fields) {
            if (f.association != association) continue;
            const hsize_t dims[2] = {steps * f.tupleCount(), hsize_t(f.components)};
            H5Handle space(H5Screate_simple(f.components == 1 ? 1 : 2, dims, nullptr), H5Sclose);
            w.ok(space.get(), "make the dataspace of " + f.name);
            datasets.emplace_back(H5Dcreate2(group.get(), f.name.c_str(), H5T_IEEE_F32LE,
                                             space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                                  H5Dclose);
            w.ok(datasets.back().get(), "create dataset " + f.name);
        }
    }
    // The fields in the order of the datasets: point fields, then cell fields.
    std::vector<const Field*> order;
    for (Association association : {Association::Point, Association::Cell})
        for (const Field& f : mesh.fields)
            if (f.association == association) order.push_back(&f);
    for (std::uint64_t k = 0; k < steps; ++k) {
        std::vector<Field> given;
        if (times) given = stepFields(k);
        const std::vector<Field>& fields = times ? given : mesh.fields;
        std::vector<const Field*> stepOrder;
        for (Association association : {Association::Point, Association::Cell})
            for (const Field& f : fields)
                if (f.association == association) stepOrder.push_back(&f);
        if (stepOrder.size() != order.size())
            throwError(ErrorKind::Argument, path,
                       "time step " + std::to_string(k) + " has " +
                           std::to_string(stepOrder.size()) + " fields, the first " +
                           std::to_string(order.size()));
        for (std::size_t i = 0; i < order.size(); ++i) {
            const Field& f = *order[i];
            const Field& g = *stepOrder[i];
            if (g.name != f.name || g.components != f.components ||
                g.values.size() != f.values.size())
                throwError(ErrorKind::Argument, path,
                           "time step " + std::to_string(k) + ": field '" + g.name +
                               "' differs from the first step's '" + f.name +
                               "' (name, components or size)");
            const hsize_t rows = f.tupleCount();
            const hsize_t start[2] = {k * rows, 0}, count[2] = {rows, hsize_t(f.components)};
            const int rank = f.components == 1 ? 1 : 2;
            H5Handle fileSpace(H5Dget_space(datasets[i].get()), H5Sclose);
            w.ok(fileSpace.get(), "read the dataspace of " + f.name);
            w.ok(H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, start, nullptr, count,
                                     nullptr),
                 "select step " + std::to_string(k) + " of " + f.name);
            H5Handle memSpace(H5Screate_simple(rank, count, nullptr), H5Sclose);
            w.ok(memSpace.get(), "make a memory dataspace");
            if (rows > 0)
                w.ok(H5Dwrite(datasets[i].get(), H5T_NATIVE_FLOAT, memSpace.get(), fileSpace.get(),
                              H5P_DEFAULT, g.values.data()),
                     "write step " + std::to_string(k) + " of " + f.name);
            report(done += g.values.size() * 4);
        }
    }
    datasets.clear();

    // The step table: one partition, the geometry shared (offsets 0), fields by step.
    if (times) {
        H5Handle group = w.group(root.get(), "Steps");
        const std::int64_t nSteps = static_cast<std::int64_t>(steps);
        H5Handle scalar(H5Screate(H5S_SCALAR), H5Sclose);
        H5Handle attr(H5Acreate2(group.get(), "NSteps", H5T_STD_I64LE, scalar.get(), H5P_DEFAULT,
                                 H5P_DEFAULT),
                      H5Aclose);
        w.ok(attr.get(), "create attribute NSteps");
        w.ok(H5Awrite(attr.get(), H5T_NATIVE_INT64, &nSteps), "write attribute NSteps");
        w.dataset(group.get(), "Values", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, steps, 0,
                  times->data());
        const std::vector<std::int64_t> zeros(steps, 0), ones(steps, 1);
        for (const char* name :
             {"PartOffsets", "PointOffsets", "CellOffsets", "ConnectivityIdOffsets"})
            w.dataset(group.get(), name, H5T_STD_I64LE, H5T_NATIVE_INT64, steps, 0, zeros.data());
        w.dataset(group.get(), "NumberOfParts", H5T_STD_I64LE, H5T_NATIVE_INT64, steps, 0,
                  ones.data());
        H5Handle pointOffsets = w.group(group.get(), "PointDataOffsets");
        H5Handle cellOffsets = w.group(group.get(), "CellDataOffsets");
        for (const Field* f : order) {
            std::vector<std::int64_t> offsets(steps);
            for (std::uint64_t k = 0; k < steps; ++k)
                offsets[k] = static_cast<std::int64_t>(k * f->tupleCount());
            w.dataset(f->association == Association::Point ? pointOffsets.get() : cellOffsets.get(),
                      f->name, H5T_STD_I64LE, H5T_NATIVE_INT64, steps, 0, offsets.data());
        }
    }
    root.reset();

    // The image, written atomically in chunks.
    const std::vector<char> bytes = w.image();
    lock.reset();
    writeOutput(path, [&](OutputFile& out) {
        constexpr std::size_t kChunk = 16u << 20;
        for (std::size_t begin = 0; begin < bytes.size(); begin += kChunk) {
            const std::size_t size = std::min(kChunk, bytes.size() - begin);
            out.write(bytes.data() + begin, size);
            if (progress) progress(0.5 + 0.5 * double(begin + size) / double(bytes.size()));
        }
    });
}

}  // namespace

void writeVtkHdf(const Mesh& mesh, const std::string& path,
                 const std::function<void(double)>& progress) {
    writeVtkHdfFile(mesh, path, progress, nullptr, {});
}

void writeVtkHdfSeries(const Mesh& mesh, const std::vector<double>& times,
                       const std::function<std::vector<Field>(std::size_t)>& stepFields,
                       const std::string& path, const std::function<void(double)>& progress) {
    writeVtkHdfFile(mesh, path, progress, &times, stepFields);
}

#endif  // UVR_HAS_HDF5

}  // namespace uvr
