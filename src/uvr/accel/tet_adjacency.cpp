// SPDX-License-Identifier: MIT
#include "uvr/accel/tet_adjacency.h"

#include <algorithm>

#include "uvr/core/error.h"

namespace uvr {

std::vector<std::uint32_t> buildTetNeighbors(const TetMesh& mesh) {
    const std::uint64_t n = mesh.tets.size();
    UVR_CHECK(n < kNoTet / 4, "too many tetrahedra for 32-bit neighbour ids");
    struct FaceKey {
        std::uint32_t a, b, c, slot;  // sorted vertex ids; slot = 4 * tet + opposite vertex
    };
    std::vector<FaceKey> faces(4 * n);
    for (std::uint64_t t = 0; t < n; ++t) {
        const auto& v = mesh.tets[t].v;
        for (int i = 0; i < 4; ++i) {
            std::uint32_t f[3], k = 0;
            for (int j = 0; j < 4; ++j)
                if (j != i) f[k++] = v[j];
            std::sort(f, f + 3);
            faces[4 * t + i] = {f[0], f[1], f[2], static_cast<std::uint32_t>(4 * t + i)};
        }
    }
    std::sort(faces.begin(), faces.end(), [](const FaceKey& x, const FaceKey& y) {
        if (x.a != y.a) return x.a < y.a;
        if (x.b != y.b) return x.b < y.b;
        return x.c < y.c;
    });
    std::vector<std::uint32_t> neighbors(4 * n, kNoTet);
    auto same = [](const FaceKey& x, const FaceKey& y) {
        return x.a == y.a && x.b == y.b && x.c == y.c;
    };
    for (std::size_t i = 0; i < faces.size();) {
        std::size_t j = i + 1;
        while (j < faces.size() && same(faces[i], faces[j])) ++j;
        if (j - i == 2) {  // an interior face; non-manifold faces (3+) stay boundary
            neighbors[faces[i].slot] = faces[i + 1].slot / 4;
            neighbors[faces[i + 1].slot] = faces[i].slot / 4;
        }
        i = j;
    }
    return neighbors;
}

}  // namespace uvr
