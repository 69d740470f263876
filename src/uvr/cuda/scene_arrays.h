// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <type_traits>

#include "uvr/prepare/prepared_mesh.h"
#include "uvr/render/adaptive_marcher.h"
#include "uvr/render/scene_view.h"

namespace uvr {

/// Whether a scene array changes with the field's values: CudaScene::updateValues re-uploads
/// those (a time step), the geometry stays. Gradients: the smooth gradients, made from the
/// values when shading first asks for them (CudaScene::uploadGradients) and with the values
/// after that.
enum class ArrayUse : std::uint8_t { Geometry, Values, Gradients };

/// The arrays of a prepared mesh that a CudaScene holds on the GPU, each declared once (issue
/// 30): A<T> is the storage (cuda::DeviceArray<T> in the scene). forEachSceneArray binds each to
/// its host source; uploads, value refreshes and byte counts all walk that one table.
template <template <class> class A>
struct SceneArrays {
    // The kernels' mesh (PreparedMesh::kernelMesh): points and values only where native cells
    // or cell data need them; tetrahedra by blocks.
    A<Vec3f> points;
    A<std::uint32_t> nativeCorners;
    A<float> values;
    A<TetCorners16> tetCorners;
    A<BlockVertex> blockVertices;
    A<std::uint32_t> blockVertexBase;
    A<NeighborCodes> neighborCodes;
    A<std::uint32_t> neighborEscapes;
    A<std::uint32_t> neighborEscapeBase;
    A<std::uint32_t> nativeNeighbors;
    A<BvhNode> bvhNodes;
    A<std::uint32_t> bvhPrims;
    A<KdNode> kdNodes;
    A<KdPartition> partitions;
    A<float> gradientSpread;
    A<std::uint8_t> partitionNan;  ///< absent when the field has no NaN
    A<BvhNode> cellTreeNodes;
    A<PartitionGrid> seedGrids;
    A<std::uint32_t> seeds;
    A<PartitionGrid> macroGrids;
    A<MacroCell> macroCells;
    A<std::uint8_t> macroNan;  ///< absent when the field has no NaN
    A<Vec3f> blockGradients;   ///< absent until shading asks for smooth gradients
    A<Vec3f> pointGradients;   ///< absent then, or without native cells
};

/// Calls f(array, host, name, use) for every array of `arrays` (a SceneArrays, or a const one):
/// `host` the prepared mesh's vector it holds, or null where the mesh has none (no native cells,
/// no partitions, no NaN: the array is then empty), `name` what an allocation failure names.
template <class Arrays, class F>
void forEachSceneArray(const PreparedMesh& m, Arrays& a, F&& f) {
    using U = ArrayUse;
    const auto some = [](bool present, const auto& v) { return present ? &v : nullptr; };
    const bool native = m.tets.hasNative(), kd = m.kd.has_value();
    f(a.points, some(native, m.tets.points), "the mesh points", U::Geometry);
    f(a.nativeCorners, some(native, m.tets.nativeCorners), "the native cells", U::Geometry);
    f(a.values, some(m.kernelMesh().values != nullptr, m.tets.values), "the field values",
      U::Values);
    f(a.tetCorners, &m.tets.tetCorners, "the tetrahedra", U::Geometry);
    f(a.blockVertices, &m.tets.blockVertices, "the tetrahedra's vertices", U::Values);
    f(a.blockVertexBase, &m.tets.blockVertexBase, "the tetrahedra's blocks", U::Geometry);
    const CompactNeighbors& nb = m.neighborCodes;
    f(a.neighborCodes, &nb.tetCodes, "the face neighbours", U::Geometry);
    f(a.neighborEscapes, &nb.escapes, "the face neighbours across blocks", U::Geometry);
    f(a.neighborEscapeBase, &nb.escapeBase, "the face neighbours' blocks", U::Geometry);
    f(a.nativeNeighbors, &nb.native, "the native cells' face neighbours", U::Geometry);
    f(a.bvhNodes, &m.bvh.nodes, "the BVH nodes", U::Geometry);
    f(a.bvhPrims, &m.bvh.primIds, "the BVH primitive ids", U::Geometry);
    f(a.kdNodes, kd ? &m.kd->nodes : nullptr, "the k-d nodes", U::Geometry);
    f(a.partitions, kd ? &m.kd->partitions : nullptr, "the partitions", U::Values);
    f(a.gradientSpread, some(kd, m.gradientSpread), "the partition gradient spreads", U::Values);
    f(a.partitionNan, some(kd && !m.partitionNan.empty(), m.partitionNan),
      "the partitions' NaN flags", U::Values);
    f(a.cellTreeNodes, some(kd, m.cellTree.nodes), "the cell tree", U::Geometry);
    f(a.seedGrids, m.seeds ? &m.seeds->grids : nullptr, "the seed grids", U::Geometry);
    f(a.seeds, m.seeds ? &m.seeds->seeds : nullptr, "the seeds", U::Geometry);
    f(a.macroGrids, m.macro ? &m.macro->grids : nullptr, "the macrocell grids", U::Geometry);
    f(a.macroCells, m.macro ? &m.macro->cells : nullptr, "the macrocells", U::Values);
    f(a.macroNan, m.macro && !m.macro->nanCells.empty() ? &m.macro->nanCells : nullptr,
      "the macrocells' NaN flags", U::Values);
    f(a.blockGradients, some(!m.tets.blockGradients.empty(), m.tets.blockGradients),
      "the smooth gradients", U::Gradients);
    f(a.pointGradients, some(native && !m.tets.pointGradients.empty(), m.tets.pointGradients),
      "the native cells' smooth gradients", U::Gradients);
}

/// Points a kernel's scene view (built on the host: counts, bounds, parameters) at the arrays'
/// copies instead of the prepared mesh's vectors: the mesh, its BVH and face neighbours. The one
/// place that says which array each pointer of a view reads; A<T> needs data().
template <template <class> class A>
void pointAtArrays(SceneView& v, const SceneArrays<A>& a) {
    TetMeshView& m = v.locator.mesh;
    m.points = a.points.data();
    m.nativeCorners = a.nativeCorners.data();
    m.values = a.values.data();
    m.tetCorners = a.tetCorners.data();
    m.blockVertices = a.blockVertices.data();
    m.blockVertexBase = a.blockVertexBase.data();
    m.blockGradients = a.blockGradients.data();  // null while absent
    m.pointGradients = a.pointGradients.data();
    v.locator.bvh.nodes = a.bvhNodes.data();
    v.locator.bvh.primIds = a.bvhPrims.data();
    v.locator.neighbors = {a.neighborCodes.data(), a.neighborEscapes.data(),
                           a.neighborEscapeBase.data(), a.nativeNeighbors.data()};
}

/// pointAtArrays for the adaptive method's view: its base scene, the k-d tree, the cell tree and
/// the seed grids (when the view has them). The per-frame shading and macrocells are the
/// caller's.
template <template <class> class A>
void pointAtArrays(PartitionSceneView& v, const SceneArrays<A>& a) {
    pointAtArrays(v.base, a);
    v.kd.nodes = a.kdNodes.data();
    v.kd.partitions = a.partitions.data();
    v.cells.nodes = a.cellTreeNodes.data();
    if (v.seeds.grids) v.seeds = {a.seedGrids.data(), a.seeds.data()};
}

/// Storage of nothing: SceneArrays<NoArray> walks the table without holding anything.
template <class T>
struct NoArray {};

/// Bytes a CudaScene of the mesh holds on the GPU (its geometryBytes once uploaded), known
/// before the upload: for progress lines.
inline std::uint64_t cudaSceneBytes(const PreparedMesh& mesh) {
    SceneArrays<NoArray> none;
    std::uint64_t n = 0;
    forEachSceneArray(mesh, none, [&](auto&, const auto* host, const char*, ArrayUse) {
        if (host)
            n += std::uint64_t(host->size()) *
                 sizeof(typename std::decay_t<decltype(*host)>::value_type);
    });
    return n;
}

}  // namespace uvr
