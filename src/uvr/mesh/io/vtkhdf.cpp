// SPDX-License-Identifier: MIT
// VTKHDF UnstructuredGrid reader (docs/FORMATS.md, section VTKHDF; the layout is Kitware's
// "VTKHDF format specification", versions 1.0 to 2.x); the writer is vtkhdf_write.cpp.
#include "uvr/mesh/io/vtkhdf.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/io/load_budget.h"

#ifdef UVR_HAS_HDF5
#include <hdf5.h>

#include <atomic>

#include "uvr/core/output_file.h"
#include "uvr/mesh/io/hdf5_handle.h"
#include "uvr/mesh/io/hdf5_structure.h"
#include "uvr/mesh/io/isolated_probe.h"
#include "uvr/mesh/io/mesh_merge.h"
#include "uvr/mesh/io/vtk_cells.h"
#include "uvr/mesh/validate.h"
#endif

namespace uvr {

namespace {

bool hasVtkHdfExtension(const std::string& path) {
    const std::string ext = fileExtension(path);
    return ext == ".vtkhdf" || ext == ".hdf";
}

}  // namespace

#ifndef UVR_HAS_HDF5

namespace {

[[noreturn]] void throwNoHdf5(const std::string& path) {
    throwError(ErrorKind::Unsupported, path,
               "this uvr was built without HDF5, which VTKHDF files need: install libhdf5-dev "
               "and rebuild");
}

}  // namespace

bool vtkHdfSupported() {
    return false;
}

bool looksLikeVtkHdf(const std::string& path) {
    return hasVtkHdfExtension(path);
}

std::unique_ptr<MeshSeries> openVtkHdfSeries(const std::string& path, const ReadOptions&) {
    throwNoHdf5(path);
}

Mesh readVtkHdf(const std::string& path, const ReadOptions&) {
    throwNoHdf5(path);
}

std::size_t vtkHdfPartitionCount(const std::string& path, std::size_t) {
    throwNoHdf5(path);
}

MeshPart readVtkHdfPart(const std::string& path, std::size_t, std::size_t, const ReadOptions&,
                        std::size_t) {
    throwNoHdf5(path);
}

void writeVtkHdf(const Mesh&, const std::string& path, const std::function<void(double)>&) {
    throwNoHdf5(path);
}

void writeVtkHdfSeries(const Mesh&, const std::vector<double>&,
                       const std::function<std::vector<Field>(std::size_t)>&,
                       const std::string& path, const std::function<void(double)>&) {
    throwNoHdf5(path);
}

#else  // UVR_HAS_HDF5

namespace {

/// The 8 bytes every HDF5 file without a user block starts with.
constexpr char kHdf5Signature[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};

constexpr std::uint64_t kMaxComponents = 1u << 20;
constexpr std::size_t kMaxStringAttribute = 4096;

/// Throws Error(Parse) "FILE: WHERE: could not WHAT (HDF5: ...)" when status is negative.
template <typename T>
T check(T status, const std::string& file, const std::string& where, const std::string& what) {
    if (status < 0) throwParseError(file, where, "could not " + what + hdf5Message());
    return status;
}

template <typename T>
hid_t memType();
template <>
hid_t memType<float>() {
    return H5T_NATIVE_FLOAT;
}
template <>
hid_t memType<double>() {
    return H5T_NATIVE_DOUBLE;
}
template <>
hid_t memType<std::int64_t>() {
    return H5T_NATIVE_INT64;
}

/// True when loc holds an object (group or dataset) at the relative path name.
bool exists(hid_t loc, const std::string& name) {
    std::size_t begin = 0;
    while (begin <= name.size()) {  // every link of the path must exist
        const std::size_t slash = name.find('/', begin);
        const std::string prefix = name.substr(0, slash);
        if (H5Lexists(loc, prefix.c_str(), H5P_DEFAULT) <= 0)
            return (H5Eclear2(H5E_DEFAULT), false);
        if (slash == std::string::npos) break;
        begin = slash + 1;
    }
    return H5Oexists_by_name(loc, name.c_str(), H5P_DEFAULT) > 0 || (H5Eclear2(H5E_DEFAULT), false);
}

/// One HDF5 dataset of the file, opened, with its shape and type.
struct Dataset {
    H5Handle id;
    std::string name;  // full path, for messages
    std::vector<hsize_t> dims;
    H5T_class_t typeClass = H5T_NO_CLASS;
    std::size_t typeBytes = 0;
    std::uint64_t storageBytes = 0;
    bool filtered = false;

    std::uint64_t rows() const { return dims.empty() ? 0 : dims[0]; }
    std::uint64_t columns() const { return dims.size() == 2 ? dims[1] : 1; }
    bool numeric() const { return typeClass == H5T_INTEGER || typeClass == H5T_FLOAT; }
};

/// An open VTKHDF file: its /VTKHDF group checked (Version, Type).
class VtkHdfFile {
public:
    explicit VtkHdfFile(const std::string& path) : path_(path) {
        quietHdf5();
        checkRegularFile(path);
        const htri_t isHdf5 = H5Fis_hdf5(path.c_str());
        if (isHdf5 <= 0) {
            H5Eclear2(H5E_DEFAULT);
            throwError(ErrorKind::Parse, path,
                       "not an HDF5 file (no HDF5 signature): expected a VTKHDF file");
        }
        file_ = H5Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
        if (file_.get() < 0)
            throwError(ErrorKind::Io, path, "HDF5 could not open the file" + hdf5Message());
        if (!exists(file_.get(), "VTKHDF") || !isGroup(file_.get(), "VTKHDF"))
            throwError(ErrorKind::Parse, path,
                       "an HDF5 file without a /VTKHDF group: not a VTKHDF file");
        root_ = H5Handle(H5Gopen2(file_.get(), "VTKHDF", H5P_DEFAULT), H5Gclose);
        check(root_.get(), path, "/VTKHDF", "open the group");
        // Version [major, minor]: 1.x and 2.x are read (minor versions only add types).
        const std::vector<std::int64_t> version = intAttribute(root_.get(), "/VTKHDF", "Version");
        if (version.size() != 2)
            throwParseError(
                path, "/VTKHDF",
                "attribute Version: expected 2 integers, got " + std::to_string(version.size()));
        if (version[0] < 1 || version[0] > 2)
            throwError(ErrorKind::Unsupported, path,
                       "/VTKHDF: Version " + std::to_string(version[0]) + "." +
                           std::to_string(version[1]) +
                           " is not supported: expected major version 1 or 2");
        // Version 1.0 files of VTK 9.1's era may lack Type: VTK 9.1 reads one with a
        // WholeExtent as ImageData and any other as an UnstructuredGrid, and so does uvr.
        const bool typeless = version[0] == 1 && H5Aexists(root_.get(), "Type") <= 0;
        const std::string type = !typeless ? stringAttribute(root_.get(), "/VTKHDF", "Type")
                                 : H5Aexists(root_.get(), "WholeExtent") > 0 ? "ImageData"
                                                                             : "UnstructuredGrid";
        if (type != "UnstructuredGrid")
            throwError(ErrorKind::Unsupported, path,
                       "/VTKHDF: Type '" + type +
                           "' is not supported: uvr reads VTKHDF files of Type UnstructuredGrid");
    }

    const std::string& path() const { return path_; }
    hid_t root() const { return root_.get(); }

    bool has(const std::string& name) const { return exists(root_.get(), name); }

    bool isGroup(hid_t loc, const std::string& name) const {
        H5Handle obj(H5Oopen(loc, name.c_str(), H5P_DEFAULT), H5Oclose);
        if (obj.get() < 0) return (H5Eclear2(H5E_DEFAULT), false);
        return H5Iget_type(obj.get()) == H5I_GROUP;
    }

    /// Opens /VTKHDF/name; Error(Parse) naming it when it is missing or not a dataset of rank 1
    /// or 2 in the contiguous, chunked or compact layout.
    Dataset dataset(const std::string& name) const {
        Dataset d;
        d.name = "/VTKHDF/" + name;
        if (!has(name)) throwParseError(path_, d.name, "missing dataset");
        if (isGroup(root_.get(), name))
            throwParseError(path_, d.name, "expected a dataset, found a group");
        d.id = H5Handle(H5Dopen2(root_.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
        check(d.id.get(), path_, d.name, "open the dataset");
        H5Handle space(H5Dget_space(d.id.get()), H5Sclose);
        check(space.get(), path_, d.name, "read the dataspace");
        const int rank =
            check(H5Sget_simple_extent_ndims(space.get()), path_, d.name, "read the dataspace");
        if (rank < 1 || rank > 2)
            throwParseError(path_, d.name,
                            "expected a dataset of 1 or 2 dimensions, got " + std::to_string(rank));
        d.dims.resize(static_cast<std::size_t>(rank));
        check(H5Sget_simple_extent_dims(space.get(), d.dims.data(), nullptr), path_, d.name,
              "read the dimensions");
        if (rank == 2 && d.dims[1] == 0)
            throwParseError(path_, d.name, "expected at least one column, got none");
        H5Handle type(H5Dget_type(d.id.get()), H5Tclose);
        check(type.get(), path_, d.name, "read the type");
        d.typeClass = H5Tget_class(type.get());
        d.typeBytes = H5Tget_size(type.get());
        H5Handle dcpl(H5Dget_create_plist(d.id.get()), H5Pclose);
        check(dcpl.get(), path_, d.name, "read the creation properties");
        const H5D_layout_t layout = H5Pget_layout(dcpl.get());
        if (layout == H5D_VIRTUAL || H5Pget_external_count(dcpl.get()) > 0)
            throwError(ErrorKind::Unsupported, path_,
                       d.name +
                           ": virtual or external datasets (data in other files) are not "
                           "supported");
        d.filtered = H5Pget_nfilters(dcpl.get()) > 0;
        d.storageBytes = H5Dget_storage_size(d.id.get());
        H5Eclear2(H5E_DEFAULT);
        return d;
    }

    /// Throws Error(Parse) naming the dataset unless it is numeric and has rows
    /// [start, start + rows); `what` says who needs them.
    void checkRows(const Dataset& d, std::uint64_t start, std::uint64_t rows,
                   const std::string& what) const {
        if (!d.numeric())
            throwParseError(path_, d.name, "expected a numeric (integer or float) dataset");
        if (start > d.rows() || rows > d.rows() - start)
            throwParseError(path_, d.name,
                            "has " + std::to_string(d.rows()) + " rows; " + what + " needs rows [" +
                                std::to_string(start) + ", " + std::to_string(start + rows) + ")");
    }

    /// Reads rows [start, start + rows) of a numeric dataset into out (rows * columns values
    /// of T); checks the range and the stored bytes first. `what` says who needs the rows.
    template <typename T>
    void readRows(const Dataset& d, std::uint64_t start, std::uint64_t rows, T* out,
                  const std::string& what) const {
        checkRows(d, start, rows, what);
        if (rows == 0 || d.columns() == 0) return;
        hsize_t offset[2] = {start, 0}, count[2] = {rows, d.columns()};
        H5Handle fileSpace(H5Dget_space(d.id.get()), H5Sclose);
        check(fileSpace.get(), path_, d.name, "read the dataspace");
        check(H5Sselect_hyperslab(fileSpace.get(), H5S_SELECT_SET, offset, nullptr, count, nullptr),
              path_, d.name, "select rows");
        H5Handle memSpace(H5Screate_simple(static_cast<int>(d.dims.size()), count, nullptr),
                          H5Sclose);
        check(memSpace.get(), path_, d.name, "make a memory dataspace");
        check(H5Dread(d.id.get(), memType<T>(), memSpace.get(), fileSpace.get(), H5P_DEFAULT, out),
              path_, d.name,
              "read rows [" + std::to_string(start) + ", " + std::to_string(start + rows) + ")");
    }

    /// Checks that rows [start, start + rows) of d exist and that the file stores enough bytes
    /// for them (a dataset cannot declare more values than it holds, beyond deflate's ratio),
    /// then charges them as T to the budget.
    template <typename T>
    void admit(const Dataset& d, std::uint64_t start, std::uint64_t rows, LoadBudget& budget,
               const std::string& what) const {
        checkRows(d, start, rows, what);
        const long double fileBytes =
            static_cast<long double>(rows) * d.columns() * static_cast<long double>(d.typeBytes);
        const long double stored =
            static_cast<long double>(d.storageBytes) * (d.filtered ? kMaxHdf5FilterRatio : 1);
        if (rows > 0 && fileBytes > stored)
            throwParseError(path_, d.name,
                            what + " needs " + std::to_string(rows) + " rows of " +
                                std::to_string(d.columns() * d.typeBytes) +
                                " bytes, but the dataset stores only " +
                                std::to_string(d.storageBytes) + " bytes" +
                                (d.filtered ? " (compressed)" : ""));
        budget.charge(path_, d.name + " (" + what + ")", rows * d.columns(), sizeof(T));
    }

    /// admit, then readRows into a new vector.
    template <typename T>
    std::vector<T> read(const Dataset& d, std::uint64_t start, std::uint64_t rows,
                        LoadBudget& budget, const std::string& what) const {
        admit<T>(d, start, rows, budget, what);
        std::vector<T> values(rows * d.columns());
        readRows(d, start, rows, values.data(), what);
        return values;
    }

    /// Every row of a dataset, first column only (the step tables, whose rows may hold more
    /// columns), checked to hold at least `rows` rows.
    std::vector<std::int64_t> firstColumn(const std::string& name, std::uint64_t rows,
                                          LoadBudget& budget, const std::string& what) const {
        const Dataset d = dataset(name);
        if (d.typeClass != H5T_INTEGER) throwParseError(path_, d.name, "expected integers");
        if (d.rows() < rows)
            throwParseError(path_, d.name,
                            "has " + std::to_string(d.rows()) + " rows, expected " +
                                std::to_string(rows) + " (" + what + ")");
        std::vector<std::int64_t> all = read<std::int64_t>(d, 0, rows, budget, what);
        std::vector<std::int64_t> first(rows);
        for (std::uint64_t r = 0; r < rows; ++r) first[r] = all[r * d.columns()];
        budget.release(all.size() * sizeof(std::int64_t));
        return first;
    }

    /// The names of the datasets (not groups) in /VTKHDF/group, in name order; empty when the
    /// group does not exist.
    std::vector<std::string> datasetNames(const std::string& group) const {
        std::vector<std::string> names;
        if (!has(group)) return names;
        const std::string where = "/VTKHDF/" + group;
        if (!isGroup(root_.get(), group)) throwParseError(path_, where, "expected a group");
        H5Handle g(H5Gopen2(root_.get(), group.c_str(), H5P_DEFAULT), H5Gclose);
        check(g.get(), path_, where, "open the group");
        H5G_info_t info;
        check(H5Gget_info(g.get(), &info), path_, where, "list the group");
        // In the order the writer created them when the group tracks it (uvr's writer does),
        // else by name.
        H5_index_t order = H5_INDEX_NAME;
        H5Handle gcpl(H5Gget_create_plist(g.get()), H5Pclose);
        unsigned flags = 0;
        if (gcpl.get() >= 0 && H5Pget_link_creation_order(gcpl.get(), &flags) >= 0 &&
            (flags & H5P_CRT_ORDER_INDEXED))
            order = H5_INDEX_CRT_ORDER;
        H5Eclear2(H5E_DEFAULT);
        for (hsize_t i = 0; i < info.nlinks; ++i) {
            const ssize_t n = check(
                H5Lget_name_by_idx(g.get(), ".", order, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT),
                path_, where, "read a member's name");
            std::string name(static_cast<std::size_t>(n) + 1, '\0');
            check(H5Lget_name_by_idx(g.get(), ".", order, H5_ITER_INC, i, name.data(), name.size(),
                                     H5P_DEFAULT),
                  path_, where, "read a member's name");
            name.resize(static_cast<std::size_t>(n));
            if (!exists(g.get(), name) || isGroup(g.get(), name)) continue;  // dangling, groups
            names.push_back(name);
        }
        return names;
    }

    /// An integer attribute of obj (all its values).
    std::vector<std::int64_t> intAttribute(hid_t obj, const std::string& where,
                                           const char* name) const {
        if (H5Aexists(obj, name) <= 0)
            throwParseError(path_, where, std::string("missing attribute ") + name);
        H5Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
        check(attr.get(), path_, where, std::string("open attribute ") + name);
        H5Handle type(H5Aget_type(attr.get()), H5Tclose);
        if (H5Tget_class(type.get()) != H5T_INTEGER)
            throwParseError(path_, where, std::string("attribute ") + name + ": expected integers");
        H5Handle space(H5Aget_space(attr.get()), H5Sclose);
        const hssize_t n = check(H5Sget_simple_extent_npoints(space.get()), path_, where,
                                 std::string("read attribute ") + name);
        if (n < 1 || n > 16)
            throwParseError(path_, where,
                            std::string("attribute ") + name + ": expected 1 to 16 integers, got " +
                                std::to_string(n));
        std::vector<std::int64_t> values(static_cast<std::size_t>(n));
        check(H5Aread(attr.get(), H5T_NATIVE_INT64, values.data()), path_, where,
              std::string("read attribute ") + name);
        return values;
    }

    /// A string attribute of obj, fixed or variable length, trailing NULs and spaces removed.
    std::string stringAttribute(hid_t obj, const std::string& where, const char* name) const {
        if (H5Aexists(obj, name) <= 0)
            throwParseError(path_, where, std::string("missing attribute ") + name);
        H5Handle attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
        check(attr.get(), path_, where, std::string("open attribute ") + name);
        H5Handle type(H5Aget_type(attr.get()), H5Tclose);
        H5Handle space(H5Aget_space(attr.get()), H5Sclose);
        if (H5Tget_class(type.get()) != H5T_STRING ||
            H5Sget_simple_extent_npoints(space.get()) != 1)
            throwParseError(path_, where,
                            std::string("attribute ") + name + ": expected one string");
        H5Handle mem(H5Tcopy(H5T_C_S1), H5Tclose);
        std::string value;
        if (H5Tis_variable_str(type.get()) > 0) {
            check(H5Tset_size(mem.get(), H5T_VARIABLE), path_, where, "make a string type");
            char* s = nullptr;
            check(H5Aread(attr.get(), mem.get(), &s), path_, where,
                  std::string("read attribute ") + name);
            if (s) value.assign(s, strnlen(s, kMaxStringAttribute));
            H5free_memory(s);
        } else {
            const std::size_t size = H5Tget_size(type.get());
            if (size == 0 || size > kMaxStringAttribute)
                throwParseError(path_, where,
                                std::string("attribute ") + name + ": a string of " +
                                    std::to_string(size) + " bytes");
            // One more byte than stored: the memory type is NUL-terminated.
            check(H5Tset_size(mem.get(), size + 1), path_, where, "make a string type");
            std::vector<char> buffer(size + 1, '\0');
            check(H5Aread(attr.get(), mem.get(), buffer.data()), path_, where,
                  std::string("read attribute ") + name);
            value.assign(buffer.data(), strnlen(buffer.data(), size));
        }
        while (!value.empty() && (value.back() == ' ' || value.back() == '\0')) value.pop_back();
        return value;
    }

private:
    std::string path_;
    H5Handle file_;
    H5Handle root_;
};

/// Where one step's geometry lies in the flattened arrays (the key of "same geometry").
struct StepGeometry {
    std::uint64_t partOffset = 0, parts = 0, pointStart = 0, cellStart = 0, connStart = 0;
    bool operator==(const StepGeometry&) const = default;
};

/// One partition of a step: its counts and where its rows start.
struct Partition {
    std::uint64_t points = 0, cells = 0, connIds = 0;
    std::uint64_t pointRow = 0, cellRow = 0, offsetsRow = 0, connRow = 0;
    std::uint64_t firstPoint = 0, firstCell = 0;  // within the step (fields add their own start)
};

/// The file's cells of a partition that were kept, when some (0D-2D cells) were dropped.
using KeptCells = std::optional<std::vector<std::uint64_t> >;

/// A point or cell field of the file.
struct FieldDesc {
    std::string name;
    Association association = Association::Point;
    std::string dataset;                   // relative to /VTKHDF
    std::vector<std::int64_t> stepOffset;  // per step, from Steps/*DataOffsets (empty: geometry's)
};

/// a + b, or Error(Parse) naming the dataset when the sum of counts overflows.
std::uint64_t addCounts(std::uint64_t a, std::uint64_t b, const std::string& file,
                        const std::string& where) {
    if (b > std::numeric_limits<std::uint64_t>::max() / 4 - a)
        throwParseError(file, where, "the counts add up to an absurd total");
    return a + b;
}

class VtkHdfSeries final : public MeshSeries {
public:
    VtkHdfSeries(const std::string& path, const ReadOptions& options,
                 std::unique_ptr<VtkHdfFile> file, std::vector<double> times,
                 std::vector<StepGeometry> steps, std::vector<FieldDesc> fields,
                 std::vector<std::string> notes, bool temporal)
        : MeshSeries(path, std::move(times), options),
          temporal_(temporal),
          file_(std::move(file)),
          steps_(std::move(steps)),
          fields_(std::move(fields)),
          notes_(std::move(notes)) {}

    ~VtkHdfSeries() override {
        const FormatLibraryLock lock;
        file_.reset();
    }

    Mesh readStep(std::size_t i) override {
        checkStep(i);
        const FormatLibraryLock lock;
        quietHdf5();
        const BudgetedOptions budgeted(options());
        LoadBudget& budget = budgeted.budget();
        const std::uint64_t heldBefore = budget.used();
        const std::vector<Partition> parts = partitions(i, budget);
        std::vector<KeptCells> kept;
        Mesh mesh = merged(i, parts, 0, parts.size(), budget, heldBefore, kept, nullptr);
        for (const std::string& note : notes_) mesh.notes.push_back(note);
        lastGeometry_ = steps_[i];
        lastKept_ = std::move(kept);
        lastCounts_ = {mesh.pointCount(), mesh.cellCount()};
        return mesh;
    }

    std::optional<std::vector<Field> > readFieldsIfSameGeometry(std::size_t i,
                                                                const MeshView& geometry) override {
        checkStep(i);
        const FormatLibraryLock lock;
        if (!lastGeometry_) return MeshSeries::readFieldsIfSameGeometry(i, geometry);
        if (!(steps_[i] == *lastGeometry_) || geometry.pointCount() != lastCounts_.first ||
            geometry.cellCount() != lastCounts_.second)
            return std::nullopt;
        quietHdf5();
        const BudgetedOptions budgeted(options());
        LoadBudget& budget = budgeted.budget();
        const std::vector<Partition> parts = partitions(i, budget);
        if (parts.size() != lastKept_.size()) return std::nullopt;
        std::vector<Field> fields;
        for (const FieldDesc& f : fields_) fields.push_back(newField(f));
        for (std::size_t p = 0; p < parts.size(); ++p) {
            std::vector<Field> pieceFields = readPartitionFields(i, p, parts[p], budget);
            for (std::size_t k = 0; k < fields_.size(); ++k) {
                Field& piece = pieceFields[k];
                fields[k].components = piece.components;
                if (piece.association == Association::Cell && lastKept_[p])
                    keepCells(piece, *lastKept_[p]);
                fields[k].values.insert(fields[k].values.end(), piece.values.begin(),
                                        piece.values.end());
            }
        }
        return fields;
    }

    /// Partitions of step i.
    const char* partName() const override { return "partitions"; }
    std::uint64_t partCount(std::size_t i) const override {
        checkStep(i);
        return steps_[i].parts;
    }

    /// Partitions [first, end) of step i, as readStep merges them, with their ids in the whole
    /// step's order (kPieceIdShift).
    MeshPart readPart(std::size_t i, std::uint64_t first, std::uint64_t end) override {
        checkStep(i);
        const FormatLibraryLock lock;
        quietHdf5();
        const BudgetedOptions budgeted(options());
        LoadBudget& budget = budgeted.budget();
        const std::uint64_t heldBefore = budget.used();
        const std::vector<Partition> parts = partitions(i, budget);
        if (first >= end || end > parts.size())
            throwError(ErrorKind::Argument, path(),
                       where(i) + ": partitions [" + std::to_string(first) + ", " +
                           std::to_string(end) + ") asked for, but it has " +
                           std::to_string(parts.size()));
        MeshPart out;
        std::vector<KeptCells> kept;
        out.mesh = merged(i, parts, first, end, budget, heldBefore, kept, &out);
        for (const std::string& note : notes_) out.mesh.notes.push_back(note);
        return out;
    }

private:
    /// Partitions [first, end) of step i merged in order (one alone as it is), the budget
    /// reset after each to what was held before plus the mesh; kept gets each one's kept cells,
    /// ids (when given) each point's and cell's id in the whole step (kPieceIdShift).
    Mesh merged(std::size_t i, const std::vector<Partition>& parts, std::size_t first,
                std::size_t end, LoadBudget& budget, std::uint64_t heldBefore,
                std::vector<KeptCells>& kept, MeshPart* ids) const {
        Mesh mesh;
        kept.assign(end - first, KeptCells{});
        for (std::size_t p = first; p < end; ++p) {
            Mesh piece = readPartition(i, p, parts[p], budget, kept[p - first]);
            if (ids) {
                const std::uint64_t base = std::uint64_t(p) << kPieceIdShift;
                for (std::uint64_t k = 0; k < piece.pointCount(); ++k)
                    ids->pointIds.push_back(base | k);
                for (std::uint64_t c = 0; c < piece.cellCount(); ++c)
                    ids->cellIds.push_back(base | c);
            }
            if (end - first == 1) {
                mesh = std::move(piece);
            } else {
                budget.charge(path(), label(i, p), meshBytes(piece), 1);  // its merged copy
                appendMeshPiece(mesh, piece, p == first, path(), where(i), label(i, p));
            }
            budget.resetTo(heldBefore + meshBytes(mesh));
        }
        return mesh;
    }

    std::string where(std::size_t i) const {
        return stepCount() > 1 || temporal_ ? "step " + std::to_string(i) : "/VTKHDF";
    }
    std::string label(std::size_t i, std::size_t p) const {
        return (temporal_ ? "step " + std::to_string(i) + ", " : std::string()) + "partition " +
               std::to_string(p);
    }

    /// The partitions of step i: their counts from NumberOfPoints/Cells/ConnectivityIds and the
    /// rows where their points, cells, offsets and connectivity start.
    std::vector<Partition> partitions(std::size_t i, LoadBudget& budget) const {
        const StepGeometry& g = steps_[i];
        const std::string what = "step " + std::to_string(i) + " (partitions [" +
                                 std::to_string(g.partOffset) + ", " +
                                 std::to_string(g.partOffset + g.parts) + "))";
        auto counts = [&](const char* name) {
            const Dataset d = file_->dataset(name);
            if (d.typeClass != H5T_INTEGER) throwParseError(path(), d.name, "expected integers");
            std::vector<std::int64_t> v =
                file_->read<std::int64_t>(d, g.partOffset, g.parts, budget, what);
            for (std::size_t k = 0; k < v.size(); ++k)
                if (v[k] < 0)
                    throwParseError(path(), d.name,
                                    "entry " + std::to_string(g.partOffset + k) +
                                        " is negative: " + std::to_string(v[k]));
            return v;
        };
        const std::vector<std::int64_t> points = counts("NumberOfPoints");
        const std::vector<std::int64_t> cells = counts("NumberOfCells");
        const std::vector<std::int64_t> conn = counts("NumberOfConnectivityIds");
        budget.charge(path(), what, g.parts, sizeof(Partition));
        std::vector<Partition> parts(g.parts);
        std::uint64_t point = 0, cell = 0, id = 0;
        for (std::size_t p = 0; p < parts.size(); ++p) {
            Partition& part = parts[p];
            part.points = static_cast<std::uint64_t>(points[p]);
            part.cells = static_cast<std::uint64_t>(cells[p]);
            part.connIds = static_cast<std::uint64_t>(conn[p]);
            part.firstPoint = point;
            part.firstCell = cell;
            part.pointRow = addCounts(g.pointStart, point, path(), "/VTKHDF/NumberOfPoints");
            part.cellRow = addCounts(g.cellStart, cell, path(), "/VTKHDF/NumberOfCells");
            // Offsets hold cells + 1 entries per partition.
            part.offsetsRow =
                addCounts(part.cellRow, g.partOffset + p, path(), "/VTKHDF/NumberOfCells");
            part.connRow = addCounts(g.connStart, id, path(), "/VTKHDF/NumberOfConnectivityIds");
            point = addCounts(point, part.points, path(), "/VTKHDF/NumberOfPoints");
            cell = addCounts(cell, part.cells, path(), "/VTKHDF/NumberOfCells");
            id = addCounts(id, part.connIds, path(), "/VTKHDF/NumberOfConnectivityIds");
        }
        budget.release((points.size() + cells.size() + conn.size()) * sizeof(std::int64_t));
        return parts;
    }

    static Field newField(const FieldDesc& f) {
        Field field;
        field.name = f.name;
        field.association = f.association;
        return field;
    }

    /// The fields of partition p of step i, one tuple per point or per cell of the file
    /// (before non-volumetric cells are dropped).
    std::vector<Field> readPartitionFields(std::size_t i, std::size_t p, const Partition& part,
                                           LoadBudget& budget) const {
        std::vector<Field> fields;
        const StepGeometry& g = steps_[i];
        for (const FieldDesc& f : fields_) {
            const Dataset d = file_->dataset(f.dataset);
            const bool point = f.association == Association::Point;
            const std::uint64_t base = f.stepOffset.empty()
                                           ? (point ? g.pointStart : g.cellStart)
                                           : static_cast<std::uint64_t>(f.stepOffset[i]);
            const std::uint64_t start =
                addCounts(base, point ? part.firstPoint : part.firstCell, path(), d.name);
            Field field = newField(f);
            field.components = static_cast<int>(d.columns());
            field.values = file_->read<float>(d, start, point ? part.points : part.cells, budget,
                                              label(i, p) + " " + (point ? "points" : "cells"));
            fields.push_back(std::move(field));
        }
        return fields;
    }

    /// Keeps the tuples of the listed cells, in order (a cell listed twice, once per
    /// tetrahedron of a decomposed one, twice).
    static void keepCells(Field& f, const std::vector<std::uint64_t>& kept) {
        const std::size_t comps = static_cast<std::size_t>(f.components);
        std::vector<float> values(kept.size() * comps);
        for (std::size_t k = 0; k < kept.size(); ++k)
            for (std::size_t c = 0; c < comps; ++c)
                values[k * comps + c] = f.values[kept[k] * comps + c];
        f.values = std::move(values);
    }

    /// Partition p of step i as a mesh; kept receives the file's cell of each mesh cell when
    /// they differ (0D-2D cells dropped, ghost cells left out, polyhedra decomposed), else stays
    /// empty.
    Mesh readPartition(std::size_t i, std::size_t p, const Partition& part, LoadBudget& budget,
                       KeptCells& kept) const {
        const std::string what = label(i, p);
        Mesh piece;
        // Points: read straight into the mesh's float triples.
        static_assert(sizeof(Vec3f) == 3 * sizeof(float), "Vec3f must be three packed floats");
        const Dataset pts = file_->dataset("Points");
        if (pts.dims.size() != 2 || pts.columns() != 3)
            throwParseError(
                path(), pts.name,
                "expected N x 3 coordinates, got " + std::to_string(pts.columns()) + " column(s)");
        file_->admit<float>(pts, part.pointRow, part.points, budget, what);
        if (part.points > std::numeric_limits<std::uint32_t>::max())
            throwError(ErrorKind::Unsupported, path(),
                       what + ": more than 4294967295 points are not supported");
        piece.points.resize(part.points);
        file_->readRows(pts, part.pointRow, part.points,
                        reinterpret_cast<float*>(piece.points.data()), what);
        piece.fields = readPartitionFields(i, p, part, budget);

        // Cells: types, offsets (cells + 1, from 0 within the partition), connectivity.
        VtkCellArrays cells;
        if (part.cells > 0) {
            const Dataset typesD = file_->dataset("Types");
            const Dataset offsetsD = file_->dataset("Offsets");
            const Dataset connD = file_->dataset("Connectivity");
            for (const Dataset* d : {&typesD, &offsetsD, &connD})
                if (d->typeClass != H5T_INTEGER || d->dims.size() != 1)
                    throwParseError(path(), d->name, "expected a 1-D dataset of integers");
            const std::vector<std::int64_t> types =
                file_->read<std::int64_t>(typesD, part.cellRow, part.cells, budget, what);
            cells.types.reserve(types.size());
            for (std::size_t c = 0; c < types.size(); ++c) {
                if (types[c] < 0 || types[c] > 255)
                    throwParseError(path(), typesD.name,
                                    what + ": cell " + std::to_string(c) +
                                        ": expected a VTK cell type in [0, 255], got " +
                                        std::to_string(types[c]));
                cells.types.push_back(static_cast<std::int32_t>(types[c]));
            }
            cells.offsets =
                file_->read<std::int64_t>(offsetsD, part.offsetsRow, part.cells + 1, budget, what);
            if (cells.offsets[0] < 0)
                throwParseError(
                    path(), offsetsD.name,
                    what + ": the first offset is negative: " + std::to_string(cells.offsets[0]));
            for (std::size_t c = 1; c < cells.offsets.size(); ++c)
                if (cells.offsets[c] < cells.offsets[c - 1])
                    throwParseError(path(), offsetsD.name,
                                    what + ": offset " + std::to_string(c) + " (" +
                                        std::to_string(cells.offsets[c]) +
                                        ") is below the one before (" +
                                        std::to_string(cells.offsets[c - 1]) +
                                        "): expected non-decreasing offsets");
            if (static_cast<std::uint64_t>(cells.offsets.back()) > part.connIds)
                throwParseError(path(), offsetsD.name,
                                what + ": the last offset is " +
                                    std::to_string(cells.offsets.back()) +
                                    ", beyond the partition's " + std::to_string(part.connIds) +
                                    " connectivity ids (NumberOfConnectivityIds)");
            cells.connectivity =
                file_->read<std::int64_t>(connD, part.connRow, part.connIds, budget, what);
            budget.charge(path(), what + ": cells", part.cells,
                          sizeof(CellType) + sizeof(std::uint64_t));
            budget.charge(path(), what + ": cell connectivity", cells.connectivity.size(),
                          sizeof(std::uint32_t));
        } else {
            cells.offsets.push_back(0);
        }
        // As in .vtu: corners of quadratic cells, voxels reordered, 0D-2D cells dropped (and
        // their cell-field tuples with them).
        std::vector<std::uint64_t> source = appendVtkCells(cells, piece, path() + ": " + what);
        bool same = source.size() == cells.types.size();
        for (std::size_t c = 0; same && c < source.size(); ++c) same = source[c] == c;
        if (!same) kept = std::move(source);
        return piece;
    }

    bool temporal_;
    std::unique_ptr<VtkHdfFile> file_;
    std::vector<StepGeometry> steps_;
    std::vector<FieldDesc> fields_;
    std::vector<std::string> notes_;
    std::optional<StepGeometry> lastGeometry_;
    std::vector<KeptCells> lastKept_;
    std::pair<std::uint64_t, std::uint64_t> lastCounts_;
};

/// The fields of /VTKHDF/PointData and /VTKHDF/CellData (numeric datasets; others noted and
/// skipped), checked for a sensible shape.
std::vector<FieldDesc> listFields(const VtkHdfFile& file, std::vector<std::string>& notes) {
    std::vector<FieldDesc> fields;
    for (const auto& [group, association] :
         {std::pair{"PointData", Association::Point}, std::pair{"CellData", Association::Cell}}) {
        for (const std::string& name : file.datasetNames(group)) {
            FieldDesc f;
            f.name = name;
            f.association = association;
            f.dataset = std::string(group) + "/" + name;
            const Dataset d = file.dataset(f.dataset);
            if (!d.numeric()) {
                notes.push_back("skipped the non-numeric " + std::string(group) + " array '" +
                                name + "'");
                continue;
            }
            if (d.columns() == 0 || d.columns() > kMaxComponents)
                throwParseError(file.path(), d.name,
                                "expected 1 to " + std::to_string(kMaxComponents) +
                                    " components (columns), got " + std::to_string(d.columns()));
            fields.push_back(std::move(f));
        }
    }
    return fields;
}

/// The step table of /VTKHDF/Steps, or one step covering the whole file (the structure pass,
/// also run in the probe child).
std::unique_ptr<MeshSeries> openSeriesHere(const std::string& path, const ReadOptions& options) {
    auto file = std::make_unique<VtkHdfFile>(path);
    const BudgetedOptions budgeted(options);
    LoadBudget& budget = budgeted.budget();
    const bool temporal = file->has("Steps");
    std::vector<std::string> notes;
    std::vector<FieldDesc> fields = listFields(*file, notes);
    std::vector<double> times;
    std::vector<StepGeometry> steps;
    if (!temporal) {
        // One step: every partition listed in NumberOfPoints, the same count in the others.
        StepGeometry g;
        g.parts = file->dataset("NumberOfPoints").rows();
        for (const char* name : {"NumberOfCells", "NumberOfConnectivityIds"}) {
            const Dataset d = file->dataset(name);
            if (d.rows() != g.parts)
                throwParseError(path, d.name,
                                "lists " + std::to_string(d.rows()) +
                                    " partition(s), /VTKHDF/NumberOfPoints lists " +
                                    std::to_string(g.parts) + ": expected one entry per partition");
        }
        steps.push_back(g);
        times.push_back(0.0);
    } else {
        if (!file->isGroup(file->root(), "Steps"))
            throwParseError(path, "/VTKHDF/Steps", "expected a group");
        H5Handle group(H5Gopen2(file->root(), "Steps", H5P_DEFAULT), H5Gclose);
        check(group.get(), path, "/VTKHDF/Steps", "open the group");
        const std::vector<std::int64_t> nSteps =
            file->intAttribute(group.get(), "/VTKHDF/Steps", "NSteps");
        if (nSteps.size() != 1 || nSteps[0] < 1)
            throwParseError(path, "/VTKHDF/Steps",
                            "attribute NSteps: expected one integer of at least 1");
        const std::uint64_t n = static_cast<std::uint64_t>(nSteps[0]);
        const std::string what = "NSteps = " + std::to_string(n);
        const auto partOffsets = file->firstColumn("Steps/PartOffsets", n, budget, what);
        const auto partCounts = file->firstColumn("Steps/NumberOfParts", n, budget, what);
        const auto pointOffsets = file->firstColumn("Steps/PointOffsets", n, budget, what);
        const auto cellOffsets = file->firstColumn("Steps/CellOffsets", n, budget, what);
        const auto connOffsets = file->firstColumn("Steps/ConnectivityIdOffsets", n, budget, what);
        for (std::uint64_t s = 0; s < n; ++s) {
            const std::pair<const char*, std::int64_t> values[] = {
                {"PartOffsets", partOffsets[s]},
                {"NumberOfParts", partCounts[s]},
                {"PointOffsets", pointOffsets[s]},
                {"CellOffsets", cellOffsets[s]},
                {"ConnectivityIdOffsets", connOffsets[s]}};
            for (const auto& [name, v] : values)
                if (v < 0)
                    throwParseError(
                        path, std::string("/VTKHDF/Steps/") + name,
                        "step " + std::to_string(s) + ": negative entry " + std::to_string(v));
            steps.push_back({static_cast<std::uint64_t>(partOffsets[s]),
                             static_cast<std::uint64_t>(partCounts[s]),
                             static_cast<std::uint64_t>(pointOffsets[s]),
                             static_cast<std::uint64_t>(cellOffsets[s]),
                             static_cast<std::uint64_t>(connOffsets[s])});
        }
        // Times: Steps/Values, else 0, 1, 2, ...
        if (file->has("Steps/Values")) {
            const Dataset d = file->dataset("Steps/Values");
            if (d.rows() < n)
                throwParseError(path, d.name,
                                "has " + std::to_string(d.rows()) + " rows, expected " +
                                    std::to_string(n) + " (" + what + ")");
            std::vector<double> all = file->read<double>(d, 0, n, budget, what);
            for (std::uint64_t s = 0; s < n; ++s) {
                times.push_back(all[s * d.columns()]);
                if (!std::isfinite(times.back()))
                    throwParseError(path, d.name,
                                    "step " + std::to_string(s) + ": the time is not finite");
            }
        } else {
            for (std::uint64_t s = 0; s < n; ++s) times.push_back(static_cast<double>(s));
        }
        // Per-field offsets: Steps/PointDataOffsets/<name>, Steps/CellDataOffsets/<name>.
        for (FieldDesc& f : fields) {
            const std::string offsets =
                std::string(f.association == Association::Point ? "Steps/PointDataOffsets/"
                                                                : "Steps/CellDataOffsets/") +
                f.name;
            if (!file->has(offsets)) continue;
            f.stepOffset = file->firstColumn(offsets, n, budget, what);
            for (std::uint64_t s = 0; s < n; ++s)
                if (f.stepOffset[s] < 0)
                    throwParseError(path, "/VTKHDF/" + offsets,
                                    "step " + std::to_string(s) + ": negative entry " +
                                        std::to_string(f.stepOffset[s]));
        }
    }
    return std::make_unique<VtkHdfSeries>(path, options, std::move(file), std::move(times),
                                          std::move(steps), std::move(fields), std::move(notes),
                                          temporal);
}

/// openSeriesHere after the same pass succeeded in a probe child, with the file's whole HDF5
/// structure walked there first (external links, external storage and virtual datasets
/// refused; every chunk index read).
std::unique_ptr<MeshSeries> openSeries(const std::string& path, const ReadOptions& options) {
    const FormatLibraryLock lock;
    checkRegularFile(path);
    std::error_code missing;
    if (!std::filesystem::exists(path, missing)) return openSeriesHere(path, options);  // says so
    const FileIdentity identity = fileIdentity(path);
    runIsolatedProbe(path, "HDF5", [&] {
        quietHdf5();
        if (H5Fis_hdf5(path.c_str()) > 0) (void)walkHdf5Structure(path);
        (void)openSeriesHere(path, options);
    });
    std::unique_ptr<MeshSeries> series = openSeriesHere(path, options);
    expectSameFile(path, identity);
    return series;
}

}  // namespace

bool vtkHdfSupported() {
    return true;
}

bool looksLikeVtkHdf(const std::string& path) {
    if (hasVtkHdfExtension(path)) return true;
    std::ifstream in(path, std::ios::binary);
    char head[8] = {};
    if (!in.read(head, sizeof head) || std::memcmp(head, kHdf5Signature, 8) != 0) return false;
    // Asked in a probe child (HDF5 may crash on the file): it answers by an error or none.
    const FormatLibraryLock lock;
    try {
        runIsolatedProbe(path, "HDF5", [&] {
            quietHdf5();
            H5Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
            const bool found = file.get() >= 0 && exists(file.get(), "VTKHDF");
            H5Eclear2(H5E_DEFAULT);
            if (!found) throwError(ErrorKind::Parse, path, "no /VTKHDF group");
        });
        return true;
    } catch (const Error&) {
        return false;
    }
}

std::unique_ptr<MeshSeries> openVtkHdfSeries(const std::string& path, const ReadOptions& options) {
    return openSeries(path, options);
}

std::size_t vtkHdfPartitionCount(const std::string& path, std::size_t step) {
    return openSeries(path, {})->partCount(step);
}

MeshPart readVtkHdfPart(const std::string& path, std::size_t first, std::size_t end,
                        const ReadOptions& options, std::size_t step) {
    return openSeries(path, options)->readPart(step, first, end);
}

Mesh readVtkHdf(const std::string& path, const ReadOptions& options) {
    return openSeries(path, options)->readStep(0);
}

#endif  // UVR_HAS_HDF5

}  // namespace uvr
