// SPDX-License-Identifier: MIT
#include "uvr/mesh/cell_types.h"

namespace uvr {

VtkCellTypeInfo vtkCellTypeInfo(int vtkType) {
    auto vol = [](CellType t, int nodes, const char* name) {
        return VtkCellTypeInfo{true, true, t, nodes, name};
    };
    auto other = [](const char* name) {
        return VtkCellTypeInfo{true, false, CellType::Tetra, 0, name};
    };
    switch (vtkType) {
        case 1:
            return other("vertex");
        case 2:
            return other("poly_vertex");
        case 3:
            return other("line");
        case 4:
            return other("poly_line");
        case 5:
            return other("triangle");
        case 6:
            return other("triangle_strip");
        case 7:
            return other("polygon");
        case 8:
            return other("pixel");
        case 9:
            return other("quad");
        case 10:
            return vol(CellType::Tetra, 4, "tetra");
        case 11:
            return vol(CellType::Hexahedron, 8, "voxel");  // reordered to a hexahedron
        case 12:
            return vol(CellType::Hexahedron, 8, "hexahedron");
        case 13:
            return vol(CellType::Wedge, 6, "wedge");
        case 14:
            return vol(CellType::Pyramid, 5, "pyramid");
        case 21:
            return other("quadratic_edge");
        case 22:
            return other("quadratic_triangle");
        case 23:
            return other("quadratic_quad");
        case 24:
            return vol(CellType::Tetra, 10, "quadratic_tetra");
        case 25:
            return vol(CellType::Hexahedron, 20, "quadratic_hexahedron");
        case 26:
            return vol(CellType::Wedge, 15, "quadratic_wedge");
        case 27:
            return vol(CellType::Pyramid, 13, "quadratic_pyramid");
        case 28:
            return other("biquadratic_quad");
        case 29:
            return vol(CellType::Hexahedron, 27, "triquadratic_hexahedron");
        case 30:
            return other("quadratic_linear_quad");
        case 31:
            return vol(CellType::Wedge, 12, "quadratic_linear_wedge");
        case 32:
            return vol(CellType::Wedge, 18, "biquadratic_quadratic_wedge");
        case 33:
            return vol(CellType::Hexahedron, 24, "biquadratic_quadratic_hexahedron");
        case 34:
            return other("biquadratic_triangle");
        case 35:
            return other("cubic_line");
        case 36:
            return other("quadratic_polygon");
        case 37:
            return vol(CellType::Pyramid, 19, "triquadratic_pyramid");
        case 42:
            return VtkCellTypeInfo{true, false, CellType::Tetra, 0, "polyhedron"};
        case 68:
            return other("lagrange_curve");
        case 69:
            return other("lagrange_triangle");
        case 70:
            return other("lagrange_quadrilateral");
        case 71:
            return vol(CellType::Tetra, 4, "lagrange_tetrahedron");
        case 72:
            return vol(CellType::Hexahedron, 8, "lagrange_hexahedron");
        case 73:
            return vol(CellType::Wedge, 6, "lagrange_wedge");
        case 74:
            return vol(CellType::Pyramid, 5, "lagrange_pyramid");
        case 75:
            return other("bezier_curve");
        case 76:
            return other("bezier_triangle");
        case 77:
            return other("bezier_quadrilateral");
        case 78:
            return vol(CellType::Tetra, 4, "bezier_tetrahedron");
        case 79:
            return vol(CellType::Hexahedron, 8, "bezier_hexahedron");
        case 80:
            return vol(CellType::Wedge, 6, "bezier_wedge");
        case 81:
            return vol(CellType::Pyramid, 5, "bezier_pyramid");
        default:
            return VtkCellTypeInfo{};
    }
}

std::string cellTypeName(CellType t) {
    switch (t) {
        case CellType::Tetra:
            return "tetra";
        case CellType::Hexahedron:
            return "hexahedron";
        case CellType::Wedge:
            return "wedge";
        case CellType::Pyramid:
            return "pyramid";
    }
    return "unknown";
}

}  // namespace uvr
