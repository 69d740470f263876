// SPDX-License-Identifier: MIT
#include "uvr/mesh/mesh.h"

#include "uvr/core/error.h"

namespace uvr {

const char* associationName(Association a) {
    return a == Association::Point ? "point" : "cell";
}

void Mesh::addCell(CellType type, std::span<const std::uint32_t> ids) {
    UVR_CHECK(static_cast<int>(ids.size()) == cornerCount(type),
              cellTypeName(type) << " given " << ids.size() << " indices");
    cellTypes.push_back(type);
    cellIndices.insert(cellIndices.end(), ids.begin(), ids.end());
    cellOffsets.push_back(cellIndices.size());
}

Bounds3f Mesh::bounds() const {
    return MeshView(*this).bounds();
}

Bounds3f MeshView::bounds() const {
    Bounds3f b;
    for (std::uint64_t c = 0; c < cellCount(); ++c) {
        const auto ids = cell(c);
        bool finite = true;
        for (std::uint32_t id : ids) finite = finite && id < points.size() && isFinite(points[id]);
        if (finite)
            for (std::uint32_t id : ids) b.extend(points[id]);
    }
    return b;
}

const Field* Mesh::findField(const std::string& name, Association association) const {
    for (const Field& f : fields)
        if (f.name == name && f.association == association) return &f;
    return nullptr;
}

}  // namespace uvr
