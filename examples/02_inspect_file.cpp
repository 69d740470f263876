// SPDX-License-Identifier: MIT
// Example 2: read a mesh file, print its fields and validation findings, and save it in the
// native format. Usage: 02_inspect_file IN.vtk|vtu [OUT.uvrm]
#include <cstdio>

#include "uvr/uvr.h"

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s IN [OUT.uvrm]\n", argv[0]);
        return 2;
    }
    try {
        const uvr::Mesh mesh = uvr::readMesh(argv[1]);
        std::printf("%llu points, %llu cells\n", static_cast<unsigned long long>(mesh.pointCount()),
                    static_cast<unsigned long long>(mesh.cellCount()));
        for (const uvr::Field& f : mesh.fields) {
            const auto s = uvr::selectScalarField(mesh, {f.name, f.association, -1});
            const auto [lo, hi] = uvr::finiteRange(s.values);
            std::printf("  %s (%s, %d components): [%g, %g]\n", f.name.c_str(),
                        uvr::associationName(f.association), f.components, lo, hi);
        }
        for (const std::string& finding : uvr::validateMesh(mesh, argv[1]).findings())
            std::printf("  finding: %s\n", finding.c_str());
        if (argc > 2) uvr::writeMesh(mesh, argv[2]);
    } catch (const uvr::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
