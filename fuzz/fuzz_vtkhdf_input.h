// SPDX-License-Identifier: MIT
#pragma once

// The structured input of the vtkhdf fuzz target: the fuzzer's bytes decide the partitions'
// counts, cell types, offsets, connectivity, coordinates, fields and time steps of a VTKHDF file,
// which is written through the HDF5 API into an in-memory file image. Fuzzing HDF5's own parser
// with raw bytes would find HDF5's bugs; this finds uvr's (counts that disagree, offsets out of
// range, steps pointing anywhere).

#include <hdf5.h>

#include "byte_reader.h"

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace uvr::fuzz {

/// Builds the in-memory HDF5 file; every HDF5 failure aborts (the input builder must not fail).
class VtkHdfImage {
public:
    VtkHdfImage() {
        H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
        const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
        ok(H5Pset_fapl_core(fapl, 1 << 16, false));
        file_ = H5Fcreate("uvr-fuzz-vtkhdf.h5", H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
        ok(file_);
        H5Pclose(fapl);
    }
    ~VtkHdfImage() {
        if (file_ >= 0) H5Fclose(file_);
    }
    hid_t file() const { return file_; }

    static void ok(long long status) {
        if (status < 0) std::abort();
    }
    hid_t group(hid_t parent, const char* name) {
        const hid_t g = H5Gcreate2(parent, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        ok(g);
        return g;
    }
    void attribute(hid_t obj, const char* name, const std::vector<std::int64_t>& values) {
        const hsize_t n = values.size();
        const hid_t space = H5Screate_simple(1, &n, nullptr);
        const hid_t a = H5Acreate2(obj, name, H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT);
        ok(a);
        ok(H5Awrite(a, H5T_NATIVE_INT64, values.data()));
        H5Aclose(a);
        H5Sclose(space);
    }
    void stringAttribute(hid_t obj, const char* name, const std::string& value) {
        const hid_t type = H5Tcopy(H5T_C_S1);
        ok(H5Tset_size(type, value.empty() ? 1 : value.size()));
        const hid_t space = H5Screate(H5S_SCALAR);
        const hid_t a = H5Acreate2(obj, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
        ok(a);
        const std::string padded = value.empty() ? std::string(1, '\0') : value;
        ok(H5Awrite(a, type, padded.data()));
        H5Aclose(a);
        H5Sclose(space);
        H5Tclose(type);
    }
    /// A dataset of rows x columns (columns 0: one dimension).
    template <typename T>
    void dataset(hid_t parent, const std::string& name, hid_t fileType, hid_t memType,
                 const std::vector<T>& values, hsize_t columns = 0) {
        const hsize_t rows = columns ? values.size() / columns : values.size();
        const hsize_t dims[2] = {rows, columns};
        const hid_t space = H5Screate_simple(columns ? 2 : 1, dims, nullptr);
        ok(space);
        const hid_t d = H5Dcreate2(parent, name.c_str(), fileType, space, H5P_DEFAULT, H5P_DEFAULT,
                                   H5P_DEFAULT);
        ok(d);
        if (rows > 0) ok(H5Dwrite(d, memType, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()));
        H5Dclose(d);
        H5Sclose(space);
    }
    void ints(hid_t parent, const std::string& name, const std::vector<std::int64_t>& v,
              hsize_t columns = 0) {
        dataset(parent, name, H5T_STD_I64LE, H5T_NATIVE_INT64, v, columns);
    }
    /// The file's bytes (the file is closed).
    std::vector<std::uint8_t> bytes() {
        ok(H5Fflush(file_, H5F_SCOPE_GLOBAL));
        const ssize_t size = H5Fget_file_image(file_, nullptr, 0);
        ok(size);
        std::vector<std::uint8_t> image(static_cast<std::size_t>(size));
        ok(H5Fget_file_image(file_, image.data(), image.size()));
        H5Fclose(file_);
        file_ = -1;
        return image;
    }

private:
    hid_t file_ = -1;
};

/// The VTKHDF file the bytes describe: 1 to 3 partitions of 0 to 11 points and 0 to 5 cells
/// (types from the VTK codes uvr knows, 0D-2D, polyhedra and any byte), connectivity ids that
/// may leave the partition, counts and offsets that may disagree, float32 or float64 points,
/// point and cell fields of 1 to 4 components (rows possibly short), and optionally a Steps
/// group of 1 to 4 steps with offsets from the bytes, a Version and Type that may be wrong.
inline std::vector<std::uint8_t> vtkHdfImage(const std::uint8_t* data, std::size_t size) {
    ByteReader in(data, size);
    const std::uint8_t flags = in.byte(), more = in.byte();
    VtkHdfImage h;
    const hid_t root = h.group(h.file(), "VTKHDF");
    h.attribute(root, "Version", {(more & 0xC0) == 0xC0 ? 3 : 1 + (flags & 1), 0});
    h.stringAttribute(root, "Type", (more & 0x30) == 0x30 ? "PolyData" : "UnstructuredGrid");

    static constexpr std::uint8_t kTypes[] = {10, 12, 13, 14, 11, 24, 25, 5, 9, 1, 42, 0};
    const int parts = 1 + (flags >> 1) % 3;
    std::vector<std::int64_t> nPoints, nCells, nConn, offsets, conn;
    std::vector<std::uint8_t> types;
    std::vector<float> xyz;
    for (int p = 0; p < parts; ++p) {
        const int points = in.byte() % 12, cells = in.byte() % 6;
        for (int k = 0; k < 3 * points; ++k) xyz.push_back(in.real());
        std::int64_t end = 0;
        const std::size_t connBefore = conn.size();
        offsets.push_back(0);
        for (int c = 0; c < cells; ++c) {
            const std::uint8_t pick = in.byte();
            const std::uint8_t type = pick % 16 < 12 ? kTypes[pick % 12] : in.byte();
            types.push_back(type);
            const int nodes = type == 12   ? 8
                              : type == 13 ? 6
                              : type == 14 ? 5
                              : type == 25 ? 20
                                           : 4;
            for (int k = 0; k < nodes; ++k) {
                const std::uint8_t id = in.byte();
                conn.push_back(id < 250 ? id % (points ? points : 1) : std::int64_t(id) - 252);
            }
            end += nodes;
            offsets.push_back(in.count(end));
        }
        nPoints.push_back(in.count(points));
        nCells.push_back(in.count(cells));
        nConn.push_back(in.count(static_cast<std::int64_t>(conn.size() - connBefore)));
    }
    h.ints(root, "NumberOfPoints", nPoints);
    h.ints(root, "NumberOfCells", nCells);
    h.ints(root,
           (flags & 0x08) && (more & 1) ? "NumberOfConnectivityIdz" : "NumberOfConnectivityIds",
           nConn);
    if (flags & 0x10) {
        std::vector<double> wide(xyz.begin(), xyz.end());
        h.dataset(root, "Points", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, wide, 3);
    } else {
        h.dataset(root, "Points", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, xyz, 3);
    }
    h.dataset(root, "Types", H5T_STD_U8LE, H5T_NATIVE_UINT8, types);
    h.ints(root, "Offsets", offsets);
    h.ints(root, "Connectivity", conn);

    // Fields: rows for every point or cell of all partitions, sometimes a few short or long.
    const auto totalPoints = static_cast<std::int64_t>(xyz.size() / 3);
    const auto totalCells = static_cast<std::int64_t>(types.size());
    const int fieldCount = in.byte() % 4;
    const hid_t pd = h.group(root, "PointData"), cd = h.group(root, "CellData");
    for (int f = 0; f < fieldCount; ++f) {
        const bool cell = in.byte() & 1;
        const int comps = 1 + in.byte() % 4;
        std::int64_t rows = in.count(cell ? totalCells : totalPoints);
        if (rows < 0 || rows > 4096) rows = 0;
        std::vector<float> values(static_cast<std::size_t>(rows * comps));
        for (float& v : values) v = in.real();
        h.dataset(cell ? cd : pd, "f" + std::to_string(f), H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, values,
                  comps == 1 ? 0 : comps);
    }

    // Time steps: offsets near the real ones, or anywhere.
    if (flags & 0x20) {
        const hid_t steps = h.group(root, "Steps");
        const int n = 1 + in.byte() % 4;
        h.attribute(steps, "NSteps", {in.count(n)});
        std::vector<std::int64_t> partOffsets, numberOfParts, pointOffsets, cellOffsets,
            connOffsets, fieldOffsets;
        std::vector<double> values;
        for (int s = 0; s < n; ++s) {
            const int part = in.byte() % parts;
            partOffsets.push_back(in.count(part));
            numberOfParts.push_back(in.count(1));
            std::int64_t points = 0, cells = 0, ids = 0;
            for (int q = 0; q < part; ++q)
                points += nPoints[q], cells += nCells[q], ids += nConn[q];
            pointOffsets.push_back(in.count(points));
            cellOffsets.push_back(in.count(cells));
            connOffsets.push_back(in.count(ids));
            fieldOffsets.push_back(in.count(0));
            values.push_back(in.real());
        }
        h.ints(steps, "PartOffsets", partOffsets);
        h.ints(steps, "NumberOfParts", numberOfParts);
        h.ints(steps, "PointOffsets", pointOffsets);
        h.ints(steps, "CellOffsets", cellOffsets, 1);
        h.ints(steps, "ConnectivityIdOffsets", connOffsets, 1);
        h.dataset(steps, "Values", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values);
        const hid_t po = h.group(steps, "PointDataOffsets");
        if (fieldCount > 0) h.ints(po, "f0", fieldOffsets);
        H5Gclose(po);
        H5Gclose(steps);
    }
    H5Gclose(pd);
    H5Gclose(cd);
    H5Gclose(root);
    return h.bytes();
}

}  // namespace uvr::fuzz
