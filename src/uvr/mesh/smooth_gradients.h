// SPDX-License-Identifier: MIT
#pragma once

// Smooth gradients for shading (issue 32): per point, the volume-weighted mean of the field
// gradients of the cells around it, interpolated inside each cell (TetMeshView::gradient with
// smooth true) as Gouraud-Phong normals are. A linear tetrahedron's own gradient is constant, so
// per-cell shading is faceted and its light jumps from cell to cell; these turn smoothly.

#include "uvr/core/progress.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

/// Fills mesh.blockGradients (per block vertex, what the kernels' tetrahedra read) and, with
/// native cells, mesh.pointGradients (per point) from the point field: each point's gradient
/// the mean of its cells' gradients weighted by their volumes (a tetrahedron's constant
/// gradient; a native cell's at that corner through its Jacobian, a pyramid's apex at the
/// middle of its axis). Cells of non-finite gradient (degenerate, NaN values) are left out; a
/// point with none gets 0 (lit as facing the light). Cell data: both empty (a constant field
/// in each cell has no gradient). A mesh without its blocks' point ids (read from a prepared
/// cache) takes the vertices at one position as one point (a sort of them). 12 bytes per block
/// vertex (and per point with native cells).
void computeSmoothGradients(TetMesh& mesh, const FractionFn& progress = {});

/// True when mesh holds what TetMeshView::gradient needs for smooth gradients (or has cell
/// data, which has none).
bool hasSmoothGradients(const TetMesh& mesh);

}  // namespace uvr
