// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/mesh_merge.h"

#include <cstdint>
#include <limits>
#include <unordered_map>

#include "uvr/core/error.h"

namespace uvr {

namespace {

std::string fieldKey(const Field& f) {
    return std::string(associationName(f.association)) + " field '" + f.name + "'";
}

/// Association and name of a field as one map key.
std::string fieldId(const Field& f) {
    return (f.association == Association::Point ? "p" : "c") + f.name;
}

/// The first field of each association and name, for merging in linear time.
std::unordered_map<std::string, Field*> indexFields(std::vector<Field>& fields) {
    std::unordered_map<std::string, Field*> index;
    index.reserve(fields.size());
    for (Field& f : fields) index.emplace(fieldId(f), &f);
    return index;
}

}  // namespace

void appendMeshPiece(Mesh& mesh, Mesh& piece, bool first, const std::string& file,
                     const std::string& where, const std::string& label) {
    const std::uint64_t pointBase = mesh.points.size();
    if (pointBase + piece.points.size() > std::numeric_limits<std::uint32_t>::max())
        throwError(ErrorKind::Unsupported, file,
                   label + ": more than 4294967295 points in all are not supported");
    // Step 1: every field of the mesh in the piece, with its components, before changing anything.
    auto pieceFields = indexFields(piece.fields);
    if (!first) {
        for (const Field& f : mesh.fields) {
            const auto found = pieceFields.find(fieldId(f));
            if (found == pieceFields.end())
                throwParseError(file, where,
                                label + " has no " + fieldKey(f) + ", which the first piece has");
            if (found->second->components != f.components)
                throwParseError(file, where,
                                label + ": " + fieldKey(f) + " has " +
                                    std::to_string(found->second->components) +
                                    " components, the first piece has " +
                                    std::to_string(f.components));
        }
        const auto meshFields = indexFields(mesh.fields);
        for (const Field& g : piece.fields)
            if (!meshFields.count(fieldId(g)))
                throwParseError(file, where,
                                label + " has " + fieldKey(g) + ", which the first piece lacks");
    }
    // Step 2: points, cells with offset indices, notes.
    const std::uint64_t indexBase = mesh.cellIndices.size();
    mesh.points.insert(mesh.points.end(), piece.points.begin(), piece.points.end());
    mesh.cellTypes.insert(mesh.cellTypes.end(), piece.cellTypes.begin(), piece.cellTypes.end());
    for (std::size_t c = 1; c < piece.cellOffsets.size(); ++c)
        mesh.cellOffsets.push_back(indexBase + piece.cellOffsets[c]);
    mesh.cellIndices.reserve(mesh.cellIndices.size() + piece.cellIndices.size());
    for (std::uint32_t id : piece.cellIndices)
        mesh.cellIndices.push_back(id + static_cast<std::uint32_t>(pointBase));
    for (const std::string& note : piece.notes) mesh.notes.push_back(label + ": " + note);
    // Step 3: fields, in the mesh's order.
    if (first) {
        mesh.fields = std::move(piece.fields);
    } else {
        for (Field& f : mesh.fields) {
            const Field& g = *pieceFields.at(fieldId(f));
            f.values.insert(f.values.end(), g.values.begin(), g.values.end());
        }
    }
    piece = Mesh{};
}

}  // namespace uvr
