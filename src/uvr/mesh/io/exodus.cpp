// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/exodus.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <unordered_map>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/io/hdf5_structure.h"
#include "uvr/mesh/io/isolated_probe.h"
#include "uvr/mesh/io/load_budget.h"

#ifdef UVR_HAVE_NETCDF
#include <netcdf.h>
#endif

namespace uvr {

bool exodusSupported() {
#ifdef UVR_HAVE_NETCDF
    return true;
#else
    return false;
#endif
}

bool looksLikeExodus(std::string_view head, const std::string& path) {
    static constexpr char kHdf5[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
    const bool netcdf = head.size() >= 4 && head.substr(0, 3) == "CDF" &&
                        (head[3] == '\x01' || head[3] == '\x02' || head[3] == '\x05');
    const bool hdf5 = head.size() >= 8 && std::memcmp(head.data(), kHdf5, 8) == 0;
    if (!netcdf && !hdf5) return false;
    const std::string ext = fileExtension(path);
    return ext == ".e" || ext == ".exo" || ext == ".ex2" || ext == ".exii" || ext == ".g" ||
           ext == ".gen";
}

Mesh readExodus(const std::string& path, const ReadOptions& options) {
    return openExodus(path, options)->readStep(0);
}

std::uint64_t exodusCellCount(const std::string& path) {
    return openExodus(path, {})->partCount(0);
}

MeshPart readExodusPart(const std::string& path, std::uint64_t first, std::uint64_t end,
                        const ReadOptions& options, std::size_t step) {
    return openExodus(path, options)->readPart(step, first, end);
}

#ifndef UVR_HAVE_NETCDF

std::unique_ptr<MeshSeries> openExodus(const std::string& path, const ReadOptions&) {
    throwError(ErrorKind::Unsupported, path,
               "this uvr was built without netCDF, so it cannot read Exodus II files: install "
               "libnetcdf-dev and rebuild");
}

#else

namespace {

/// Throws Error(Parse) "FILE: WHAT: netCDF's message" unless status is success (NC_ERANGE, a
/// double beyond float's range, is read as +-Inf: validation reports it).
void ncCheck(int status, const std::string& file, const std::string& what) {
    if (status == NC_NOERR || status == NC_ERANGE) return;
    throwError(ErrorKind::Parse, file, what + ": " + nc_strerror(status));
}

/// An open netCDF file (closed on destruction) and the look-ups the reader needs.
class NcFile {
public:
    explicit NcFile(const std::string& path) : path_(path) {
        checkRegularFile(path);
        if (!std::filesystem::exists(path))
            throwError(ErrorKind::Io, path, "cannot open: no such file");
        const int status = nc_open(path.c_str(), NC_NOWRITE, &id_);
        if (status != NC_NOERR) {
            id_ = -1;
            throwError(
                ErrorKind::Parse, path,
                std::string("not a readable netCDF (Exodus II) file: ") + nc_strerror(status));
        }
    }
    ~NcFile() {
        if (id_ >= 0) nc_close(id_);
    }
    NcFile(const NcFile&) = delete;
    NcFile& operator=(const NcFile&) = delete;

    int id() const { return id_; }
    const std::string& path() const { return path_; }

    /// The length of a dimension, or nullopt when the file has none of that name.
    std::optional<std::size_t> dim(const std::string& name) const {
        int d = -1;
        if (nc_inq_dimid(id_, name.c_str(), &d) != NC_NOERR) return std::nullopt;
        std::size_t len = 0;
        ncCheck(nc_inq_dimlen(id_, d, &len), path_, "dimension " + name);
        return len;
    }
    /// A variable's id, or -1 when the file has none of that name.
    int var(const std::string& name) const {
        int v = -1;
        return nc_inq_varid(id_, name.c_str(), &v) == NC_NOERR ? v : -1;
    }
    /// A variable's dimension lengths.
    std::vector<std::size_t> shape(int varid) const {
        int ndims = 0;
        ncCheck(nc_inq_varndims(id_, varid, &ndims), path_, "a variable's dimensions");
        std::vector<int> dims(static_cast<std::size_t>(std::max(ndims, 0)));
        if (ndims > 0) ncCheck(nc_inq_vardimid(id_, varid, dims.data()), path_, "dimensions");
        std::vector<std::size_t> lens(dims.size());
        for (std::size_t k = 0; k < dims.size(); ++k)
            ncCheck(nc_inq_dimlen(id_, dims[k], &lens[k]), path_, "a dimension's length");
        return lens;
    }
    /// Throws Error(Parse) naming the variable unless its shape is `expected` (what: its role).
    void expectShape(int varid, const std::string& name, const std::vector<std::size_t>& expected,
                     const std::string& what) const {
        const std::vector<std::size_t> got = shape(varid);
        if (got == expected) return;
        auto text = [](const std::vector<std::size_t>& s) {
            std::string t = "(";
            for (std::size_t k = 0; k < s.size(); ++k) t += (k ? ", " : "") + std::to_string(s[k]);
            return t + ")";
        };
        throwError(ErrorKind::Parse, path_,
                   "variable " + name + " has shape " + text(got) + ", expected " + text(expected) +
                       " " + what);
    }
    /// A text attribute of a variable, "" when absent or not text.
    std::string textAttribute(int varid, const char* name) const {
        nc_type type = NC_NAT;
        std::size_t len = 0;
        if (nc_inq_att(id_, varid, name, &type, &len) != NC_NOERR || type != NC_CHAR || len > 4096)
            return "";
        std::string s(len, '\0');
        if (len) ncCheck(nc_get_att_text(id_, varid, name, s.data()), path_, name);
        return trim(s);
    }
    /// The count names of a (count, length) char variable, "" for each when it is absent.
    std::vector<std::string> names(const std::string& name, std::size_t count) const {
        const int v = var(name);
        if (v < 0 || count == 0) return std::vector<std::string>(count);
        const std::vector<std::size_t> s = shape(v);
        if (s.size() != 2 || s[0] != count || s[1] > 4096)
            throwError(ErrorKind::Parse, path_,
                       "variable " + name + ": expected " + std::to_string(count) +
                           " names of at most 4096 characters");
        std::vector<std::string> out(count);
        std::string text(count * s[1], '\0');
        if (!text.empty()) ncCheck(nc_get_var_text(id_, v, text.data()), path_, name);
        for (std::size_t i = 0; i < count; ++i) out[i] = trim(text.substr(i * s[1], s[1]));
        return out;
    }

    /// Text up to its first NUL, without trailing blanks.
    static std::string trim(const std::string& s) {
        std::string t = s.substr(0, s.find('\0'));
        while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
        return t;
    }

private:
    std::string path_;
    int id_ = -1;
};

/// How an element block's elem_type is read.
struct BlockType {
    bool volume = false;  ///< a tetrahedron, hexahedron, wedge or pyramid family
    CellType cell{};
    std::array<int, 8> corners{};  ///< node positions (0-based) of VTK's corners, in VTK order
    const char* family = "";
};

/// The volume families by elem_type prefix (as VTK's reader matches them), with the node counts
/// their members have (corner nodes first in each, as the Exodus II manual numbers them).
BlockType blockType(const std::string& elemType) {
    std::string t;
    for (char c : elemType) t += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    BlockType b;
    b.corners = {0, 1, 2, 3, 4, 5, 6, 7};
    if (t.rfind("TET", 0) == 0) {
        b = {true, CellType::Tetra, b.corners, "TETRA"};
    } else if (t.rfind("HEX", 0) == 0 && t.rfind("HEXSHELL", 0) != 0) {
        b = {true, CellType::Hexahedron, b.corners, "HEX"};
    } else if (t.rfind("WEDGE", 0) == 0) {
        b = {true, CellType::Wedge, b.corners, "WEDGE"};
    } else if (t.rfind("PYRA", 0) == 0) {
        b = {true, CellType::Pyramid, b.corners, "PYRAMID"};
    }
    return b;
}

/// Node counts a block of a volume family may have.
std::vector<std::size_t> allowedNodes(CellType type) {
    switch (type) {
        case CellType::Tetra:
            return {4, 8, 10, 11, 14, 15};
        case CellType::Hexahedron:
            return {8, 9, 20, 27};
        case CellType::Wedge:
            return {6, 12, 15, 16, 18, 20, 21};
        case CellType::Pyramid:
            return {5, 13, 14, 18, 19};
    }
    return {};
}

/// An element block as the file declares it.
struct Block {
    std::size_t index = 0;  ///< N of connectN, num_el_in_blkN (1-based)
    long long id = 0;       ///< eb_prop1 (the block id users see)
    std::string name, elemType;
    std::size_t elements = 0, nodesPerElement = 0;
    int connectVar = -1;
    BlockType type;
    bool kept = false;
    std::uint64_t firstCell = 0;  ///< index of its first cell in the mesh (kept blocks)

    /// "block ID 3 ('name', connect2)" for messages.
    std::string label() const {
        return "block ID " + std::to_string(id) + (name.empty() ? "" : " ('" + name + "')") +
               " (connect" + std::to_string(index) + ")";
    }
};

/// A field made of one or three file variables (VTK's reader groups NAMEX, NAMEY, NAMEZ).
struct FieldGroup {
    std::string name;
    std::vector<std::size_t> variables;  ///< indices into the variable names, one per component
};

/// Groups consecutive names ending in X, Y, Z (case-insensitive, the same non-empty prefix) into
/// vectors named by the prefix, as VTK's Exodus reader: VX, VY, VZ is V; vel_x, vel_y, vel_z is
/// vel_ (as ParaView names it).
std::vector<FieldGroup> groupComponents(const std::vector<std::string>& names) {
    std::vector<FieldGroup> groups;
    for (std::size_t i = 0; i < names.size();) {
        if (i + 2 < names.size()) {
            const std::string& a = names[i];
            const std::size_t n = a.size();
            auto last = [](const std::string& s) {
                return static_cast<char>(std::tolower(static_cast<unsigned char>(s.back())));
            };
            bool vector = n >= 2 && names[i + 1].size() == n && names[i + 2].size() == n &&
                          last(a) == 'x' && last(names[i + 1]) == 'y' &&
                          last(names[i + 2]) == 'z' &&
                          names[i + 1].compare(0, n - 1, a, 0, n - 1) == 0 &&
                          names[i + 2].compare(0, n - 1, a, 0, n - 1) == 0;
            const std::string prefix = a.substr(0, n - 1);
            if (vector && prefix != "_") {
                groups.push_back({prefix, {i, i + 1, i + 2}});
                i += 3;
                continue;
            }
        }
        groups.push_back({names[i].empty() ? "variable" + std::to_string(i + 1) : names[i], {i}});
        ++i;
    }
    return groups;
}

/// Reads a whole variable as long long or int (by its type in the file) into out.
template <typename T>
void readAll(const NcFile& f, int varid, std::vector<T>& out, const std::string& what) {
    if (out.empty()) return;
    if constexpr (std::is_same_v<T, int>)
        ncCheck(nc_get_var_int(f.id(), varid, out.data()), f.path(), what);
    else
        ncCheck(nc_get_var_longlong(f.id(), varid, out.data()), f.path(), what);
}

/// Reads rows [first, first + count) of a 2-D variable (all its columns) as long long or int.
template <typename T>
void readRows(const NcFile& f, int varid, std::size_t first, std::size_t count, std::size_t columns,
              std::vector<T>& out, const std::string& what) {
    out.resize(count * columns);
    if (out.empty()) return;
    const std::size_t start[2] = {first, 0}, counts[2] = {count, columns};
    if constexpr (std::is_same_v<T, int>)
        ncCheck(nc_get_vara_int(f.id(), varid, start, counts, out.data()), f.path(), what);
    else
        ncCheck(nc_get_vara_longlong(f.id(), varid, start, counts, out.data()), f.path(), what);
}

/// An Exodus II file's steps: the metadata read at open, the arrays at each step.
class ExodusSeries final : public MeshSeries {
public:
    ExodusSeries(std::unique_ptr<NcFile> file, std::vector<double> times, std::size_t records,
                 const ReadOptions& options)
        : MeshSeries(file->path(), std::move(times), options),
          file_(std::move(file)),
          records_(records) {
        readLayout();
    }
    ~ExodusSeries() override {
        const FormatLibraryLock lock;
        file_.reset();
    }

    Mesh readStep(std::size_t i) override {
        checkStep(i);
        const FormatLibraryLock lock;
        const BudgetedOptions budgeted(options());
        LoadBudget& budget = budgeted.budget();
        const std::uint64_t heldBefore = budget.used();
        Mesh mesh;
        readPoints(mesh, budget);
        readCells(mesh, budget);
        mesh.fields = readFields(i, budget);
        mesh.notes = notes_;
        budget.resetTo(heldBefore + meshBytes(mesh));
        return mesh;
    }

    std::optional<std::vector<Field> > readFieldsIfSameGeometry(std::size_t i,
                                                                const MeshView& geometry) override {
        checkStep(i);
        const FormatLibraryLock lock;
        if (geometry.pointCount() != nodes_ || geometry.cellCount() != keptCells_ ||
            geometry.cellIndices.size() != keptIndices_)
            return std::nullopt;
        const BudgetedOptions budgeted(options());
        return readFields(i, budgeted.budget());
    }

    /// Cells the mesh of a step holds (the kept blocks' elements): a rank's part is a run of them.
    const char* partName() const override { return "cells"; }
    std::uint64_t partCount(std::size_t i) const override {
        checkStep(i);
        return keptCells_;
    }

    /// The cells [first, end) of step i and what they use, as meshPart takes them from
    /// readStep(i): the blocks' connectivity read only over those cells' rows, the coordinates
    /// and nodal variables over the span of node numbers they use.
    MeshPart readPart(std::size_t i, std::uint64_t first, std::uint64_t end) override {
        checkStep(i);
        const FormatLibraryLock lock;
        if (first > end || end > keptCells_)
            throwError(ErrorKind::Argument, file(),
                       "cells [" + std::to_string(first) + ", " + std::to_string(end) +
                           ") asked for, but the file has " + std::to_string(keptCells_));
        const BudgetedOptions budgeted(options());
        LoadBudget& budget = budgeted.budget();
        MeshPart part;
        Mesh& mesh = part.mesh;
        // Step 1: the cells' corners as node numbers (0-based), block by block.
        std::vector<std::uint64_t> corners;
        for (const Block& block : blocks_) {
            if (!block.kept) continue;
            const std::uint64_t b0 = std::max<std::uint64_t>(first, block.firstCell);
            const std::uint64_t b1 = std::min<std::uint64_t>(end, block.firstCell + block.elements);
            if (b0 >= b1) continue;
            nc_type type = NC_NAT;
            ncCheck(nc_inq_vartype(file_->id(), block.connectVar, &type), file(), block.label());
            if (type == NC_INT64 || type == NC_UINT64 || type == NC_UINT)
                partOfBlock<long long>(block, b0, b1, mesh, corners, budget);
            else
                partOfBlock<int>(block, b0, b1, mesh, corners, budget);
        }
        for (std::uint64_t c = first; c < end; ++c) part.cellIds.push_back(c);
        // Step 2: the nodes they use, in the file's order, and the corners as their indices.
        part.pointIds = corners;
        std::sort(part.pointIds.begin(), part.pointIds.end());
        part.pointIds.erase(std::unique(part.pointIds.begin(), part.pointIds.end()),
                            part.pointIds.end());
        mesh.cellIndices.reserve(corners.size());
        for (std::uint64_t id : corners)
            mesh.cellIndices.push_back(static_cast<std::uint32_t>(
                std::lower_bound(part.pointIds.begin(), part.pointIds.end(), id) -
                part.pointIds.begin()));
        std::vector<std::uint64_t>().swap(corners);
        // Step 3: coordinates and nodal variables over the span of those nodes.
        const std::size_t lo = part.pointIds.empty() ? 0 : part.pointIds.front();
        const std::size_t span = part.pointIds.empty() ? 0 : part.pointIds.back() + 1 - lo;
        budget.charge(file(), "the part's points", part.pointIds.size(), sizeof(Vec3f));
        budget.charge(file(), "a span of a nodal array", span, sizeof(float));
        std::vector<float> window(span);
        mesh.points.resize(part.pointIds.size());
        static const char* const kNames[3] = {"coordx", "coordy", "coordz"};
        for (int d = 0; d < 3 && span > 0; ++d) {
            if (coordVar_ >= 0) {
                const std::size_t start[2] = {static_cast<std::size_t>(d), lo};
                const std::size_t count[2] = {1, span};
                ncCheck(nc_get_vara_float(file_->id(), coordVar_, start, count, window.data()),
                        file(), "variable coord");
            } else {
                const std::size_t start[1] = {lo}, count[1] = {span};
                ncCheck(nc_get_vara_float(file_->id(), coordVars_[d], start, count, window.data()),
                        file(), std::string("variable ") + kNames[d]);
            }
            for (std::size_t k = 0; k < part.pointIds.size(); ++k)
                mesh.points[k][d] = window[part.pointIds[k] - lo];
        }
        if (records_ > 0) {
            for (const FieldGroup& g : pointGroups_) {
                const int comps = static_cast<int>(g.variables.size());
                Field field{g.name, Association::Point, comps,
                            std::vector<float>(part.pointIds.size() * comps)};
                for (int c = 0; c < comps && span > 0; ++c) {
                    const std::size_t v = g.variables[c];
                    const std::string what = "the nodal variable '" + nodVarNames_[v] + "'";
                    if (combinedNodVar_ >= 0) {
                        const std::size_t start[3] = {i, v, lo}, count[3] = {1, 1, span};
                        ncCheck(nc_get_vara_float(file_->id(), combinedNodVar_, start, count,
                                                  window.data()),
                                file(), what + " (vals_nod_var)");
                    } else {
                        const std::size_t start[2] = {i, lo}, count[2] = {1, span};
                        ncCheck(nc_get_vara_float(file_->id(), nodVarIds_[v], start, count,
                                                  window.data()),
                                file(), what);
                    }
                    for (std::size_t k = 0; k < part.pointIds.size(); ++k)
                        field.values[k * comps + c] = window[part.pointIds[k] - lo];
                }
                mesh.fields.push_back(std::move(field));
            }
            // Element variables over the part's rows of each block.
            for (const FieldGroup& g : cellGroups_) {
                const int comps = static_cast<int>(g.variables.size());
                Field field{g.name, Association::Cell, comps,
                            std::vector<float>((end - first) * comps,
                                               std::numeric_limits<float>::quiet_NaN())};
                for (const Block& block : blocks_) {
                    if (!block.kept) continue;
                    const std::uint64_t b0 = std::max<std::uint64_t>(first, block.firstCell);
                    const std::uint64_t b1 =
                        std::min<std::uint64_t>(end, block.firstCell + block.elements);
                    if (b0 >= b1) continue;
                    std::vector<float> rows(b1 - b0);
                    for (int c = 0; c < comps; ++c) {
                        const std::size_t v = g.variables[c];
                        const int id = elemVarIds_[v][block.index - 1];
                        if (id < 0) continue;
                        const std::size_t start[2] = {i, b0 - block.firstCell},
                                          count[2] = {1, b1 - b0};
                        ncCheck(
                            nc_get_vara_float(file_->id(), id, start, count, rows.data()), file(),
                            "the element variable '" + elemVarNames_[v] + "' on " + block.label());
                        for (std::uint64_t e = b0; e < b1; ++e)
                            field.values[(e - first) * comps + c] = rows[e - b0];
                    }
                }
                mesh.fields.push_back(std::move(field));
            }
        }
        mesh.notes = notes_;
        return part;
    }

private:
    const std::string& file() const { return path(); }

    /// The cells [b0, b1) (mesh cell indices) of a kept block: their types and offsets into
    /// `mesh`, their corners' node numbers (0-based, checked) onto `corners`.
    template <typename T>
    void partOfBlock(const Block& block, std::uint64_t b0, std::uint64_t b1, Mesh& mesh,
                     std::vector<std::uint64_t>& corners, LoadBudget& budget) const {
        const std::uint64_t rows = b1 - b0;
        budget.charge(file(), block.label() + ": connectivity", rows * block.nodesPerElement,
                      sizeof(T));
        std::vector<T> conn;
        readRows(*file_, block.connectVar, b0 - block.firstCell, rows, block.nodesPerElement, conn,
                 "variable connect" + std::to_string(block.index));
        const CellType cell = block.type.cell;
        const int count = cornerCount(cell);
        for (std::uint64_t r = 0; r < rows; ++r) {
            const T* nodes = conn.data() + r * block.nodesPerElement;
            for (int k = 0; k < count; ++k) {
                const long long id = nodes[block.type.corners[k]];
                if (id < 1 || static_cast<std::uint64_t>(id) > nodes_)
                    throwError(ErrorKind::Validation, file(),
                               block.label() + ", element " +
                                   std::to_string(b0 - block.firstCell + r + 1) + ": node " +
                                   std::to_string(id) + " out of range [1, " +
                                   std::to_string(nodes_) + "] (num_nodes)");
                corners.push_back(static_cast<std::uint64_t>(id - 1));
            }
            mesh.cellTypes.push_back(cell);
            mesh.cellOffsets.push_back(corners.size());
        }
        budget.release(rows * block.nodesPerElement * sizeof(T));
    }

    /// Step titles: dimensions, coordinates, blocks, variable names and truth table; every
    /// variable read later is checked for its shape here.
    void readLayout() {
        const NcFile& f = *file_;
        // Dimensions and coordinates.
        const std::optional<std::size_t> numDim = f.dim("num_dim");
        if (!numDim)
            throwError(ErrorKind::Parse, file(),
                       "no num_dim dimension: not an Exodus II file (or not one uvr reads)");
        if (*numDim != 3)
            throwError(ErrorKind::Unsupported, file(),
                       "num_dim is " + std::to_string(*numDim) + ": a " + std::to_string(*numDim) +
                           "D mesh holds no volume cells (uvr renders 3D meshes)");
        nodes_ = f.dim("num_nodes").value_or(0);
        if (nodes_ > std::numeric_limits<std::uint32_t>::max())
            throwError(ErrorKind::Unsupported, file(),
                       "num_nodes is " + std::to_string(nodes_) + ": more than 2^32 - 1 points");
        if (nodes_ > 0) {
            const char* names[3] = {"coordx", "coordy", "coordz"};
            for (int d = 0; d < 3; ++d) {
                coordVars_[d] = f.var(names[d]);
                if (coordVars_[d] >= 0)
                    f.expectShape(coordVars_[d], names[d], {nodes_}, "(num_nodes coordinates)");
            }
            if (coordVars_[0] < 0 || coordVars_[1] < 0 || coordVars_[2] < 0) {
                coordVar_ = f.var("coord");
                if (coordVar_ < 0)
                    throwError(ErrorKind::Parse, file(),
                               "no coordinates: expected the variables coordx, coordy, coordz "
                               "(or coord of shape (num_dim, num_nodes))");
                f.expectShape(coordVar_, "coord", {3, nodes_}, "(num_dim, num_nodes)");
            }
        }
        readBlocks();
        readVariables();
    }

    void readBlocks() {
        const NcFile& f = *file_;
        const std::size_t count = f.dim("num_el_blk").value_or(0);
        if (count > 1'000'000)
            throwError(ErrorKind::Resource, file(),
                       "num_el_blk is " + std::to_string(count) + ": more than a million blocks");
        std::vector<long long> ids(count);
        if (const int v = f.var("eb_prop1"); v >= 0 && count) {
            f.expectShape(v, "eb_prop1", {count}, "(one id per element block)");
            readAll(f, v, ids, "eb_prop1");
        } else {
            for (std::size_t b = 0; b < count; ++b) ids[b] = static_cast<long long>(b + 1);
        }
        const std::vector<std::string> names = f.names("eb_names", count);
        for (std::size_t b = 0; b < count; ++b) {
            Block block;
            block.index = b + 1;
            block.id = ids[b];
            block.name = names[b];
            const std::string n = std::to_string(block.index);
            block.elements = f.dim("num_el_in_blk" + n).value_or(0);
            if (block.elements == 0) {
                blocks_.push_back(block);
                continue;
            }
            block.nodesPerElement = f.dim("num_nod_per_el" + n).value_or(0);
            block.connectVar = f.var("connect" + n);
            if (block.connectVar < 0)
                throwError(ErrorKind::Parse, file(),
                           block.label() + ": the block has " + std::to_string(block.elements) +
                               " elements but no connect" + n + " variable");
            block.elemType = f.textAttribute(block.connectVar, "elem_type");
            block.type = blockType(block.elemType);
            if (!block.type.volume) {
                notes_.push_back("dropped " + block.label() + ": " +
                                 std::to_string(block.elements) + " " +
                                 (block.elemType.empty() ? "untyped" : block.elemType) +
                                 " element(s), not volume cells");
                blocks_.push_back(block);
                continue;
            }
            checkNodeCount(block);
            f.expectShape(block.connectVar, "connect" + n, {block.elements, block.nodesPerElement},
                          "(num_el_in_blk" + n + ", num_nod_per_el" + n + ")");
            block.kept = true;
            block.firstCell = keptCells_;
            keptCells_ += block.elements;
            keptIndices_ += block.elements * cornerCount(block.type.cell);
            if (block.nodesPerElement != static_cast<std::size_t>(cornerCount(block.type.cell)))
                notes_.push_back("reduced " + std::to_string(block.elements) + " " +
                                 block.elemType + " cell(s) of " + block.label() +
                                 " to their corner nodes: their mid-edge and higher-order nodes "
                                 "are used by no cell, and fields are interpolated between the "
                                 "corners");
            blocks_.push_back(block);
        }
    }

    /// Error(Parse) unless the block's nodes per element fit its elem_type (HEX8: 8; HEX: one
    /// of the hexahedron family's counts).
    void checkNodeCount(const Block& block) const {
        const std::vector<std::size_t> allowed = allowedNodes(block.type.cell);
        std::string digits;
        for (auto it = block.elemType.rbegin();
             it != block.elemType.rend() && std::isdigit(static_cast<unsigned char>(*it)); ++it)
            digits.insert(digits.begin(), *it);
        const std::string n = std::to_string(block.index);
        std::string list;
        for (std::size_t a : allowed) list += (list.empty() ? "" : ", ") + std::to_string(a);
        const bool suffixDisagrees =
            !digits.empty() && digits.size() < 4 && std::stoul(digits) != block.nodesPerElement;
        if (suffixDisagrees ||
            std::find(allowed.begin(), allowed.end(), block.nodesPerElement) == allowed.end())
            throwError(ErrorKind::Parse, file(),
                       block.label() + ": elem_type '" + block.elemType + "' with " +
                           std::to_string(block.nodesPerElement) +
                           " nodes per element (num_nod_per_el" + n + "), expected " +
                           (suffixDisagrees ? digits : "one of " + list) + " for a " +
                           block.type.family);
    }

    /// Error(Parse) when a count dimension (num_nod_var, num_elem_var) declares more variables
    /// than the file has and no variable of that dimension (holder) stores them: nothing is
    /// allocated for counts only a header declares.
    void checkVariableCount(const char* dim, std::size_t count, const char* holder) const {
        const NcFile& f = *file_;
        int nvars = 0;
        ncCheck(nc_inq_nvars(f.id(), &nvars), file(), "the variables");
        if (count <= static_cast<std::size_t>(std::max(nvars, 0)) || f.var(holder) >= 0) return;
        throwError(ErrorKind::Parse, file(),
                   std::string(dim) + " is " + std::to_string(count) + ", but the file has " +
                       std::to_string(nvars) + " variables and no " + holder +
                       ": each of its variables needs one");
    }

    void readVariables() {
        const NcFile& f = *file_;
        // Nodal variables: vals_nod_var1..N, or the old combined vals_nod_var (step, var, node).
        const std::size_t nodVars = f.dim("num_nod_var").value_or(0);
        if (f.var("vals_nod_var") < 0) checkVariableCount("num_nod_var", nodVars, "name_nod_var");
        nodVarNames_ = f.names("name_nod_var", nodVars);
        if (nodVars && records_) {
            combinedNodVar_ = f.var("vals_nod_var");
            if (combinedNodVar_ >= 0) {
                f.expectShape(combinedNodVar_, "vals_nod_var", {records_, nodVars, nodes_},
                              "(time_step, num_nod_var, num_nodes)");
            } else {
                for (std::size_t v = 0; v < nodVars; ++v) {
                    const std::string name = "vals_nod_var" + std::to_string(v + 1);
                    const int id = f.var(name);
                    if (id < 0)
                        throwError(ErrorKind::Parse, file(),
                                   "no variable " + name + " for the nodal variable '" +
                                       nodVarNames_[v] + "' (num_nod_var is " +
                                       std::to_string(nodVars) + ")");
                    f.expectShape(id, name, {records_, nodes_}, "(time_step, num_nodes)");
                    nodVarIds_.push_back(id);
                }
            }
            pointGroups_ = groupComponents(nodVarNames_);
            for (const FieldGroup& g : pointGroups_) {
                std::string upper;
                for (char c : g.name)
                    upper += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
                if (g.variables.size() == 3 && upper.rfind("DISP", 0) == 0)
                    notes_.push_back("the nodal variable " + g.name +
                                     " is read as a field; the geometry is not displaced by it");
            }
        }
        // Element variables: vals_elem_var{v}eb{b} where the truth table elem_var_tab says so.
        const std::size_t elemVars = f.dim("num_elem_var").value_or(0);
        const int tableVar = f.var("elem_var_tab");
        if (tableVar < 0) checkVariableCount("num_elem_var", elemVars, "name_elem_var");
        elemVarNames_ = f.names("name_elem_var", elemVars);
        if (!elemVars || !records_ || keptCells_ == 0) return;
        // Without a stored truth table, every (variable, block) pair is looked up: bounded.
        if (tableVar < 0 && elemVars * blocks_.size() > (std::size_t{1} << 24))
            throwError(ErrorKind::Resource, file(),
                       "num_elem_var (" + std::to_string(elemVars) + ") times num_el_blk (" +
                           std::to_string(blocks_.size()) +
                           ") without an elem_var_tab: more than 2^24 variable slots");
        std::vector<int> table;
        if (const int t = tableVar; t >= 0) {
            f.expectShape(t, "elem_var_tab", {blocks_.size(), elemVars},
                          "(num_el_blk, num_elem_var)");
            table.resize(blocks_.size() * elemVars);
            readAll(f, t, table, "elem_var_tab");
        }
        elemVarIds_.assign(elemVars, std::vector<int>(blocks_.size(), -1));
        for (std::size_t v = 0; v < elemVars; ++v) {
            for (std::size_t b = 0; b < blocks_.size(); ++b) {
                const Block& block = blocks_[b];
                if (!block.kept) continue;
                const std::string name =
                    "vals_elem_var" + std::to_string(v + 1) + "eb" + std::to_string(block.index);
                const int id = f.var(name);
                const bool listed = table.empty() || table[b * elemVars + v] != 0;
                if (listed && id >= 0) {
                    f.expectShape(id, name, {records_, block.elements},
                                  "(time_step, num_el_in_blk" + std::to_string(block.index) + ")");
                    elemVarIds_[v][b] = id;
                } else if (listed && !table.empty()) {
                    throwError(ErrorKind::Parse, file(),
                               "no variable " + name +
                                   ", which elem_var_tab lists for the element "
                                   "variable '" +
                                   elemVarNames_[v] + "' on " + block.label());
                }
            }
        }
        cellGroups_ = groupComponents(elemVarNames_);
        for (const FieldGroup& g : cellGroups_)
            for (const Block& block : blocks_) {
                if (!block.kept) continue;
                const std::size_t b = block.index - 1;
                const bool missing =
                    std::any_of(g.variables.begin(), g.variables.end(),
                                [&](std::size_t v) { return elemVarIds_[v][b] < 0; });
                if (missing)
                    notes_.push_back("the element variable " + g.name + " is not defined on " +
                                     block.label() + ": its " + std::to_string(block.elements) +
                                     " cells get NaN");
            }
    }

    void readPoints(Mesh& mesh, LoadBudget& budget) const {
        const NcFile& f = *file_;
        budget.charge(file(), "the points", nodes_, sizeof(Vec3f));
        mesh.points.resize(nodes_);
        if (nodes_ == 0) return;
        budget.charge(file(), "a coordinate array", nodes_, sizeof(float));
        std::vector<float> c(nodes_);
        static const char* const kNames[3] = {"coordx", "coordy", "coordz"};
        for (int d = 0; d < 3; ++d) {
            if (coordVar_ >= 0) {
                const std::size_t start[2] = {static_cast<std::size_t>(d), 0};
                const std::size_t count[2] = {1, nodes_};
                ncCheck(nc_get_vara_float(f.id(), coordVar_, start, count, c.data()), file(),
                        "variable coord");
            } else {
                ncCheck(nc_get_var_float(f.id(), coordVars_[d], c.data()), file(),
                        std::string("variable ") + kNames[d]);
            }
            for (std::size_t k = 0; k < nodes_; ++k) mesh.points[k][d] = c[k];
        }
        budget.release(nodes_ * sizeof(float));
    }

    void readCells(Mesh& mesh, LoadBudget& budget) const {
        budget.charge(file(), "the cells", keptCells_, sizeof(CellType) + sizeof(std::uint64_t));
        budget.charge(file(), "the cell connectivity", keptIndices_, sizeof(std::uint32_t));
        mesh.cellTypes.reserve(keptCells_);
        mesh.cellOffsets.reserve(keptCells_ + 1);
        mesh.cellIndices.reserve(keptIndices_);
        for (const Block& block : blocks_) {
            if (!block.kept) continue;
            nc_type type = NC_NAT;
            ncCheck(nc_inq_vartype(file_->id(), block.connectVar, &type), file(), block.label());
            if (type == NC_INT64 || type == NC_UINT64 || type == NC_UINT)
                appendBlock<long long>(block, mesh, budget);
            else
                appendBlock<int>(block, mesh, budget);
        }
    }

    /// Appends a block's cells, its connectivity read whole as T and checked against num_nodes.
    template <typename T>
    void appendBlock(const Block& block, Mesh& mesh, LoadBudget& budget) const {
        const std::uint64_t entries =
            static_cast<std::uint64_t>(block.elements) * block.nodesPerElement;
        budget.charge(file(), block.label() + ": connectivity", entries, sizeof(T));
        std::vector<T> conn(entries);
        readAll(*file_, block.connectVar, conn, "variable connect" + std::to_string(block.index));
        const CellType cell = block.type.cell;
        const int corners = cornerCount(cell);
        for (std::size_t e = 0; e < block.elements; ++e) {
            const T* nodes = conn.data() + e * block.nodesPerElement;
            for (int k = 0; k < corners; ++k) {
                const long long id = nodes[block.type.corners[k]];
                if (id < 1 || static_cast<std::uint64_t>(id) > nodes_)
                    throwError(ErrorKind::Validation, file(),
                               block.label() + ", element " + std::to_string(e + 1) + ": node " +
                                   std::to_string(id) + " out of range [1, " +
                                   std::to_string(nodes_) + "] (num_nodes)");
                mesh.cellIndices.push_back(static_cast<std::uint32_t>(id - 1));
            }
            mesh.cellTypes.push_back(cell);
            mesh.cellOffsets.push_back(mesh.cellIndices.size());
        }
        budget.release(entries * sizeof(T));
    }

    /// Step i's nodal and element variables as point and cell fields.
    std::vector<Field> readFields(std::size_t i, LoadBudget& budget) const {
        std::vector<Field> fields;
        if (records_ == 0) return fields;
        const NcFile& f = *file_;
        std::vector<float> tmp;
        for (const FieldGroup& g : pointGroups_) {
            const int comps = static_cast<int>(g.variables.size());
            budget.charge(file(), "the point field " + g.name, nodes_ * comps, sizeof(float));
            Field field{g.name, Association::Point, comps, std::vector<float>(nodes_ * comps)};
            if (comps > 1) {
                budget.charge(file(), "a nodal variable", nodes_, sizeof(float));
                tmp.resize(nodes_);
            }
            for (int c = 0; c < comps; ++c) {
                const std::size_t v = g.variables[c];
                float* out = comps == 1 ? field.values.data() : tmp.data();
                const std::string what = "the nodal variable '" + nodVarNames_[v] + "'";
                if (nodes_ == 0) continue;
                if (combinedNodVar_ >= 0) {
                    const std::size_t start[3] = {i, v, 0}, count[3] = {1, 1, nodes_};
                    ncCheck(nc_get_vara_float(f.id(), combinedNodVar_, start, count, out), file(),
                            what + " (vals_nod_var)");
                } else {
                    const std::size_t start[2] = {i, 0}, count[2] = {1, nodes_};
                    ncCheck(nc_get_vara_float(f.id(), nodVarIds_[v], start, count, out), file(),
                            what);
                }
                if (comps > 1)
                    for (std::size_t k = 0; k < nodes_; ++k) field.values[k * comps + c] = tmp[k];
            }
            if (comps > 1) {
                budget.release(nodes_ * sizeof(float));
                std::vector<float>().swap(tmp);
            }
            fields.push_back(std::move(field));
        }
        for (const FieldGroup& g : cellGroups_) {
            const int comps = static_cast<int>(g.variables.size());
            budget.charge(file(), "the cell field " + g.name, keptCells_ * comps, sizeof(float));
            Field field{
                g.name, Association::Cell, comps,
                std::vector<float>(keptCells_ * comps, std::numeric_limits<float>::quiet_NaN())};
            for (const Block& block : blocks_) {
                if (!block.kept) continue;
                const std::size_t b = block.index - 1;
                budget.charge(file(), "an element variable", block.elements, sizeof(float));
                tmp.resize(block.elements);
                for (int c = 0; c < comps; ++c) {
                    const std::size_t v = g.variables[c];
                    const int id = elemVarIds_[v][b];
                    if (id < 0) continue;
                    const std::size_t start[2] = {i, 0}, count[2] = {1, block.elements};
                    ncCheck(nc_get_vara_float(f.id(), id, start, count, tmp.data()), file(),
                            "the element variable '" + elemVarNames_[v] + "' on " + block.label());
                    for (std::size_t e = 0; e < block.elements; ++e)
                        field.values[(block.firstCell + e) * comps + c] = tmp[e];
                }
                budget.release(block.elements * sizeof(float));
            }
            std::vector<float>().swap(tmp);
            fields.push_back(std::move(field));
        }
        return fields;
    }

    std::unique_ptr<NcFile> file_;
    std::size_t records_ = 0;  ///< records of the time_step dimension
    std::size_t nodes_ = 0;
    int coordVars_[3] = {-1, -1, -1};
    int coordVar_ = -1;  ///< the old combined coord (num_dim, num_nodes), when used
    std::vector<Block> blocks_;
    std::uint64_t keptCells_ = 0, keptIndices_ = 0;
    std::vector<std::string> nodVarNames_, elemVarNames_;
    std::vector<int> nodVarIds_;
    int combinedNodVar_ = -1;
    std::vector<std::vector<int> > elemVarIds_;  ///< [variable][block]: varid or -1
    std::vector<FieldGroup> pointGroups_, cellGroups_;
    std::vector<std::string> notes_;
};

}  // namespace

namespace {

/// Error(Parse) naming the variable when a classic-format file (CDF-1, -2, -5) is shorter than
/// its variables' data (a record variable's is its record size times the records): netCDF reads
/// past the end as fill values without an error, so a small file could declare gigabytes.
void checkClassicSize(const NcFile& f) {
    int format = 0;
    ncCheck(nc_inq_format(f.id(), &format), f.path(), "the netCDF format");
    if (format != NC_FORMAT_CLASSIC && format != NC_FORMAT_64BIT_OFFSET && format != NC_FORMAT_CDF5)
        return;  // netCDF-4: checkNetcdf4Storage
    int nvars = 0;
    ncCheck(nc_inq_nvars(f.id(), &nvars), f.path(), "the variables");
    const std::uint64_t size = fileSize(f.path());
    std::uint64_t needed = 32;  // the smallest header
    for (int v = 0; v < nvars; ++v) {
        nc_type type = NC_NAT;
        int ndims = 0;
        ncCheck(nc_inq_vartype(f.id(), v, &type), f.path(), "a variable's type");
        ncCheck(nc_inq_varndims(f.id(), v, &ndims), f.path(), "a variable's dimensions");
        std::size_t typeSize = 0;
        ncCheck(nc_inq_type(f.id(), type, nullptr, &typeSize), f.path(), "a variable's type");
        std::vector<int> dims(static_cast<std::size_t>(std::max(ndims, 0)));
        if (ndims > 0) ncCheck(nc_inq_vardimid(f.id(), v, dims.data()), f.path(), "dimensions");
        long double bytes = static_cast<long double>(typeSize);
        for (int d : dims) {
            std::size_t len = 0;
            ncCheck(nc_inq_dimlen(f.id(), d, &len), f.path(), "a dimension's length");
            bytes *= static_cast<long double>(len);
        }
        const long double total = static_cast<long double>(needed) + bytes;
        if (total > static_cast<long double>(size)) {
            char name[NC_MAX_NAME + 1] = {};
            ncCheck(nc_inq_varname(f.id(), v, name), f.path(), "a variable's name");
            throwError(ErrorKind::Parse, f.path(),
                       "variable " + std::string(name) + " declares " +
                           std::to_string(static_cast<unsigned long long>(
                               std::min(bytes, static_cast<long double>(1e19)))) +
                           " bytes, which with the variables before it need " +
                           std::to_string(static_cast<unsigned long long>(
                               std::min(total, static_cast<long double>(1e19)))) +
                           " bytes: the file has " + std::to_string(size) +
                           " (truncated or a lying header)");
        }
        needed = static_cast<std::uint64_t>(total);
    }
}

/// Error(Parse) naming the variable when a netCDF-4 (HDF5) file declares more of a variable
/// than it stores (beyond deflate's ratio when compressed): unwritten chunks read as fill values,
/// so a small file could otherwise declare gigabytes of coordinates or millions of time steps.
void checkNetcdf4Storage(const NcFile& f, const std::vector<Hdf5DatasetInfo>& datasets) {
    std::unordered_map<std::string, const Hdf5DatasetInfo*> byName;
    for (const Hdf5DatasetInfo& d : datasets) byName.emplace(d.name, &d);
    int nvars = 0;
    ncCheck(nc_inq_nvars(f.id(), &nvars), f.path(), "the variables");
    for (int v = 0; v < nvars; ++v) {
        char name[NC_MAX_NAME + 1] = {};
        ncCheck(nc_inq_varname(f.id(), v, name), f.path(), "a variable's name");
        // netCDF-4 stores a variable as the dataset of its name (prefixed when it would clash
        // with a dimension's).
        for (const std::string& dataset :
             {std::string(name), "_nc4_non_coord_" + std::string(name)})
            if (const auto it = byName.find(dataset); it != byName.end())
                expectStored(f.path(), std::string("variable ") + name, *it->second);
    }
}

/// Opens and checks the file, reads its times and layout (the structure pass, also run in the
/// probe child): every netCDF call the metadata needs, none of the bulk arrays.
std::unique_ptr<MeshSeries> openExodusHere(const std::string& path, const ReadOptions& options) {
    checkRegularFile(path);
    if (!std::filesystem::exists(path))
        throwError(ErrorKind::Io, path, "cannot open: no such file");
    // A netCDF-4 file is walked with HDF5 first: external links and storage are refused before
    // netCDF could follow them, and each dataset's stored bytes bound what it may declare.
    std::vector<Hdf5DatasetInfo> datasets;
    char head[8] = {};
    std::ifstream in(path, std::ios::binary);
    const bool hdf5 = in.read(head, 8) && std::memcmp(head, "\x89HDF\r\n\x1a\n", 8) == 0;
    if (hdf5 && hdf5WalkSupported()) datasets = walkHdf5Structure(path);
    auto file = std::make_unique<NcFile>(path);
    checkClassicSize(*file);
    if (hdf5) checkNetcdf4Storage(*file, datasets);
    // Time steps: time_whole over the time_step records; none is one step at time 0.
    const std::size_t records = file->dim("time_step").value_or(0);
    std::vector<double> times{0.0};
    if (records > 0) {
        const int v = file->var("time_whole");
        if (v < 0)
            throwError(ErrorKind::Parse, path,
                       "the file has " + std::to_string(records) +
                           " time_step records but no time_whole variable");
        file->expectShape(v, "time_whole", {records}, "(one per time_step record)");
        checkAllocation(path, "time_whole", records, sizeof(double), options.maxMemoryBytes);
        times.resize(records);
        ncCheck(nc_get_var_double(file->id(), v, times.data()), path, "variable time_whole");
    }
    return std::make_unique<ExodusSeries>(std::move(file), std::move(times), records, options);
}

}  // namespace

std::unique_ptr<MeshSeries> openExodus(const std::string& path, const ReadOptions& options) {
    const FormatLibraryLock lock;
    checkRegularFile(path);
    std::error_code missing;
    if (!std::filesystem::exists(path, missing)) return openExodusHere(path, options);  // says so
    const FileIdentity identity = fileIdentity(path);
    // netCDF and HDF5 crash or hang on some malformed files: the structure pass runs first in
    // a child process, and the file is opened here only when it succeeded there.
    runIsolatedProbe(path, "netCDF", [&] { (void)openExodusHere(path, options); });
    std::unique_ptr<MeshSeries> series = openExodusHere(path, options);
    expectSameFile(path, identity);
    return series;
}

#endif

}  // namespace uvr
