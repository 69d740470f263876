// SPDX-License-Identifier: MIT
#pragma once

// Writes small Exodus II files through the netCDF C API, as the Exodus library lays them out
// (and, on request, with the mistakes a bad file holds): the Exodus reader's tests and its
// structured fuzz target build their inputs with it. Needs netcdf.h (UVR_HAVE_NETCDF).

#include <netcdf.h>

#include <algorithm>
#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "uvr/mesh/mesh.h"

namespace uvr::testing {

/// An element block: its id, elem_type, nodes per element and 1-based connectivity.
struct ExoBlock {
    long long id = 1;
    std::string elemType;
    std::size_t nodesPerElement = 0;
    std::vector<long long> connect;  ///< elements * nodesPerElement node numbers (1-based)
    std::string name;
    /// Elements of the block (connect.size() / nodesPerElement).
    std::size_t elements() const { return nodesPerElement ? connect.size() / nodesPerElement : 0; }
};

/// What an Exodus II file holds, and how it is laid out.
struct ExoFileSpec {
    int numDim = 3;
    std::vector<double> x, y, z;     ///< node coordinates (num_nodes each)
    bool writeCoordinates = true;    ///< false: no coordinate variable at all (a bad file)
    bool combinedCoord = false;      ///< the old coord(num_dim, num_nodes) instead of coordx/y/z
    bool combinedNodalVars = false;  ///< the old vals_nod_var(time_step, num_nod_var, num_nodes)
    bool netcdf4 = false;            ///< netCDF-4 (HDF5) instead of the 64-bit-offset format
    bool doubles = false;            ///< coordinates, times and values as NC_DOUBLE
    std::vector<ExoBlock> blocks;
    std::vector<std::string> nodalVars, elemVars;
    std::vector<int> truthTable;  ///< num_el_blk x num_elem_var; empty: every variable everywhere
    std::vector<double> times;    ///< one per time_step record; empty: no records
    /// Value of nodal variable v at step s, node n.
    std::function<double(std::size_t s, std::size_t v, std::size_t n)> nodal;
    /// Value of element variable v at step s, block b, element e.
    std::function<double(std::size_t s, std::size_t v, std::size_t b, std::size_t e)> element;
    /// When set, the dimension vals_nod_var1 is defined on instead of num_nodes (a bad file).
    std::string firstNodalVarDim;
};

/// Throws std::runtime_error naming the call unless status is NC_NOERR.
inline void ncOk(int status, const std::string& what) {
    if (status != NC_NOERR) throw std::runtime_error(what + ": " + nc_strerror(status));
}

/// Writes spec to path (replacing it); throws std::runtime_error when netCDF fails.
inline void writeExodusFile(const std::string& path, const ExoFileSpec& spec) {
    int nc = -1;
    ncOk(nc_create(path.c_str(), NC_CLOBBER | (spec.netcdf4 ? NC_NETCDF4 : NC_64BIT_OFFSET), &nc),
         "nc_create " + path);
    struct Closer {
        int id;
        ~Closer() { nc_close(id); }
    } closer{nc};
    const nc_type real = spec.doubles ? NC_DOUBLE : NC_FLOAT;
    auto dim = [&](const std::string& name, std::size_t len) {
        int d = -1;
        ncOk(nc_def_dim(nc, name.c_str(), len, &d), "dimension " + name);
        return d;
    };
    auto var = [&](const std::string& name, nc_type type, std::vector<int> dims) {
        int v = -1;
        ncOk(nc_def_var(nc, name.c_str(), type, static_cast<int>(dims.size()), dims.data(), &v),
             "variable " + name);
        return v;
    };
    const std::size_t nodes = spec.x.size(), nb = spec.blocks.size();
    const std::size_t nnv = spec.nodalVars.size(), nev = spec.elemVars.size();
    // Definitions (a dimension of length 0 would be unlimited: counts of 0 define none).
    // What the Exodus library (and so VTK's reader) needs to open the file.
    // (an old layout as the 1990s library wrote it, e.g. disk_out_ref.ex2: version 2.02).
    const bool old = spec.combinedCoord || spec.combinedNodalVars;
    const float version = old ? 2.02f : 8.11f;
    const int wordSize = spec.doubles ? 8 : 4, fileSize = 1, nameLength = 32;
    ncOk(nc_put_att_float(nc, NC_GLOBAL, "api_version", NC_FLOAT, 1, &version), "api_version");
    ncOk(nc_put_att_float(nc, NC_GLOBAL, "version", NC_FLOAT, 1, &version), "version");
    ncOk(nc_put_att_int(nc, NC_GLOBAL, "floating_point_word_size", NC_INT, 1, &wordSize),
         "floating_point_word_size");
    ncOk(nc_put_att_int(nc, NC_GLOBAL, "file_size", NC_INT, 1, &fileSize), "file_size");
    ncOk(nc_put_att_int(nc, NC_GLOBAL, "maximum_name_length", NC_INT, 1, &nameLength),
         "maximum_name_length");
    dim("len_string", 33);
    dim("len_line", 81);
    dim("four", 4);
    std::size_t elements = 0;
    for (const ExoBlock& block : spec.blocks) elements += block.elements();
    if (elements) dim("num_elem", elements);
    const int lenName = dim("len_name", 33);
    const int time = dim("time_step", NC_UNLIMITED);
    const int numDim = dim("num_dim", static_cast<std::size_t>(spec.numDim));
    const int numNodes = nodes ? dim("num_nodes", nodes) : -1;
    const int numBlk = nb ? dim("num_el_blk", nb) : -1;
    const int vTime = var("time_whole", real, {time});
    int vStatus = -1, vIds = -1, vNames = -1, vCoord = -1, vXyz[3] = {-1, -1, -1};
    if (nb) {
        vStatus = var("eb_status", NC_INT, {numBlk});
        vIds = var("eb_prop1", NC_INT, {numBlk});
        ncOk(nc_put_att_text(nc, vIds, "name", 2, "ID"), "eb_prop1 name");
        vNames = var("eb_names", NC_CHAR, {numBlk, lenName});
    }
    if (spec.writeCoordinates && nodes) {
        if (spec.combinedCoord) {
            vCoord = var("coord", real, {numDim, numNodes});
        } else {
            const char* names[3] = {"coordx", "coordy", "coordz"};
            for (int d = 0; d < spec.numDim && d < 3; ++d)
                vXyz[d] = var(names[d], real, {numNodes});
        }
    }
    std::vector<int> vConnect(nb, -1), blockDim(nb, -1);
    for (std::size_t b = 0; b < nb; ++b) {
        const ExoBlock& block = spec.blocks[b];
        if (block.elements() == 0) continue;
        const std::string n = std::to_string(b + 1);
        blockDim[b] = dim("num_el_in_blk" + n, block.elements());
        const int npe = dim("num_nod_per_el" + n, block.nodesPerElement);
        vConnect[b] = var("connect" + n, NC_INT, {blockDim[b], npe});
        ncOk(nc_put_att_text(nc, vConnect[b], "elem_type", block.elemType.size(),
                             block.elemType.c_str()),
             "elem_type");
    }
    int vNodNames = -1, vNodCombined = -1, vElemNames = -1, vTab = -1;
    std::vector<int> vNod(nnv, -1);
    std::vector<std::vector<int>> vElem(nev, std::vector<int>(nb, -1));
    if (nnv) {
        const int numNodVar = dim("num_nod_var", nnv);
        vNodNames = var("name_nod_var", NC_CHAR, {numNodVar, lenName});
        if (spec.combinedNodalVars) {
            vNodCombined = var("vals_nod_var", real, {time, numNodVar, numNodes});
        } else {
            for (std::size_t v = 0; v < nnv; ++v) {
                int d = numNodes;
                if (v == 0 && !spec.firstNodalVarDim.empty())
                    ncOk(nc_inq_dimid(nc, spec.firstNodalVarDim.c_str(), &d), "bad dimension");
                vNod[v] = var("vals_nod_var" + std::to_string(v + 1), real, {time, d});
            }
        }
    }
    auto defined = [&](std::size_t b, std::size_t v) {
        return spec.truthTable.empty() || spec.truthTable[b * nev + v] != 0;
    };
    if (nev) {
        const int numElemVar = dim("num_elem_var", nev);
        vElemNames = var("name_elem_var", NC_CHAR, {numElemVar, lenName});
        if (!spec.truthTable.empty() && nb)
            vTab = var("elem_var_tab", NC_INT, {numBlk, numElemVar});
        for (std::size_t v = 0; v < nev; ++v)
            for (std::size_t b = 0; b < nb; ++b)
                if (blockDim[b] >= 0 && defined(b, v))
                    vElem[v][b] =
                        var("vals_elem_var" + std::to_string(v + 1) + "eb" + std::to_string(b + 1),
                            real, {time, blockDim[b]});
    }
    ncOk(nc_enddef(nc), "nc_enddef");
    // Data.
    auto putName = [&](int v, std::size_t i, const std::string& s) {
        const std::size_t start[2] = {i, 0}, count[2] = {1, std::min<std::size_t>(s.size(), 32)};
        if (count[1]) ncOk(nc_put_vara_text(nc, v, start, count, s.c_str()), "a name");
    };
    for (std::size_t b = 0; b < nb; ++b) {
        const ExoBlock& block = spec.blocks[b];
        const std::size_t i[1] = {b};
        const int id = static_cast<int>(block.id);
        ncOk(nc_put_var1_int(nc, vIds, i, &id), "eb_prop1");
        const int status = block.elements() ? 1 : 0;
        ncOk(nc_put_var1_int(nc, vStatus, i, &status), "eb_status");
        putName(vNames, b, block.name);
        if (vConnect[b] < 0) continue;
        const std::vector<int> c(block.connect.begin(), block.connect.end());
        ncOk(nc_put_var_int(nc, vConnect[b], c.data()), "connect");
    }
    const std::vector<double>* xyz[3] = {&spec.x, &spec.y, &spec.z};
    for (int d = 0; d < 3 && d < spec.numDim; ++d) {
        if (vCoord >= 0) {
            const std::size_t start[2] = {static_cast<std::size_t>(d), 0}, count[2] = {1, nodes};
            ncOk(nc_put_vara_double(nc, vCoord, start, count, xyz[d]->data()), "coord");
        } else if (vXyz[d] >= 0) {
            ncOk(nc_put_var_double(nc, vXyz[d], xyz[d]->data()), "coordx/y/z");
        }
    }
    for (std::size_t v = 0; v < nnv; ++v) putName(vNodNames, v, spec.nodalVars[v]);
    for (std::size_t v = 0; v < nev; ++v) putName(vElemNames, v, spec.elemVars[v]);
    if (vTab >= 0) ncOk(nc_put_var_int(nc, vTab, spec.truthTable.data()), "elem_var_tab");
    for (std::size_t s = 0; s < spec.times.size(); ++s) {
        const std::size_t ts[1] = {s};
        ncOk(nc_put_var1_double(nc, vTime, ts, &spec.times[s]), "time_whole");
        for (std::size_t v = 0; v < nnv; ++v) {
            std::size_t len = nodes;
            if (v == 0 && !spec.firstNodalVarDim.empty())
                ncOk(nc_inq_dimlen(
                         nc,
                         [&] {
                             int d = -1;
                             nc_inq_dimid(nc, spec.firstNodalVarDim.c_str(), &d);
                             return d;
                         }(),
                         &len),
                     "bad dimension length");
            std::vector<double> values(len);
            for (std::size_t n = 0; n < len; ++n) values[n] = spec.nodal ? spec.nodal(s, v, n) : 0;
            if (!len) continue;
            if (vNodCombined >= 0) {
                const std::size_t start[3] = {s, v, 0}, count[3] = {1, 1, len};
                ncOk(nc_put_vara_double(nc, vNodCombined, start, count, values.data()),
                     "vals_nod_var");
            } else {
                const std::size_t start[2] = {s, 0}, count[2] = {1, len};
                ncOk(nc_put_vara_double(nc, vNod[v], start, count, values.data()), "vals_nod_var");
            }
        }
        for (std::size_t v = 0; v < nev; ++v)
            for (std::size_t b = 0; b < nb; ++b) {
                if (vElem[v][b] < 0) continue;
                const std::size_t ne = spec.blocks[b].elements();
                std::vector<double> values(ne);
                for (std::size_t e = 0; e < ne; ++e)
                    values[e] = spec.element ? spec.element(s, v, b, e) : 0;
                const std::size_t start[2] = {s, 0}, count[2] = {1, ne};
                ncOk(nc_put_vara_double(nc, vElem[v][b], start, count, values.data()),
                     "vals_elem_var");
            }
    }
}

/// A mesh of hexahedra as one HEX8 block with the nodal variable "f" over `steps` time steps
/// (times 0, 1, ...): value(step, node).
inline ExoFileSpec hexSeriesSpec(const Mesh& hexes, std::size_t steps,
                                 std::function<double(std::size_t, std::size_t)> value) {
    ExoFileSpec spec;
    for (const Vec3f& p : hexes.points) {
        spec.x.push_back(p.x);
        spec.y.push_back(p.y);
        spec.z.push_back(p.z);
    }
    spec.blocks = {{1, "HEX8", 8, {}, "hexes"}};
    for (std::uint32_t id : hexes.cellIndices) spec.blocks[0].connect.push_back(id + 1);
    spec.nodalVars = {"f"};
    for (std::size_t s = 0; s < steps; ++s) spec.times.push_back(double(s));
    spec.nodal = [value](std::size_t s, std::size_t, std::size_t n) { return value(s, n); };
    return spec;
}

}  // namespace uvr::testing
