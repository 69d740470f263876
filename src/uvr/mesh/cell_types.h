// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>

namespace uvr {

/// Volumetric cell types uvr renders, with VTK's type codes and vertex order.
enum class CellType : std::uint8_t {
    Tetra = 10,
    Hexahedron = 12,
    Wedge = 13,
    Pyramid = 14,
};

/// Number of corner vertices of a volumetric cell type.
constexpr int cornerCount(CellType t) {
    switch (t) {
        case CellType::Tetra:
            return 4;
        case CellType::Hexahedron:
            return 8;
        case CellType::Wedge:
            return 6;
        case CellType::Pyramid:
            return 5;
    }
    return 0;
}

/// How uvr treats a VTK cell type code found in a file.
struct VtkCellTypeInfo {
    bool known = false;       ///< a VTK cell type code at all
    bool volumetric = false;  ///< a 3D cell uvr renders (linear, quadratic or Lagrange)
    CellType linear{};        ///< the linear type read through the cell's corner nodes
    int minNodes = 0;         ///< fewest nodes a cell of this type may list
    const char* name = "";    ///< VTK's name of the type
};

/// Classifies a VTK cell type code: quadratic/Lagrange 3D cells map to their linear corner type
/// (corners come first in VTK's node order), 0D-2D cells are known but not volumetric.
VtkCellTypeInfo vtkCellTypeInfo(int vtkType);

/// Name of a volumetric cell type ("tetra", "hexahedron", ...).
std::string cellTypeName(CellType t);

}  // namespace uvr
