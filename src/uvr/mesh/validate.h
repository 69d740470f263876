// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "uvr/core/progress.h"
#include "uvr/mesh/mesh.h"

namespace uvr {

/// Non-finite values found in one field.
struct NonFiniteField {
    std::string name;
    Association association = Association::Point;
    std::uint64_t count = 0;
    std::uint64_t firstTuple = 0;  ///< first point/cell index holding a NaN or Inf
};

/// One finding of validation, for machines (`uvr info --json`) and people (message).
struct ValidationFinding {
    /// What was found: inverted_cells, zero_volume_cells, distorted_cells, coincident_points,
    /// non_finite_points, unused_points, non_finite_field_values.
    std::string code;
    std::uint64_t count = 0;
    /// "cell", "point" or, for field values, the field's association; with `first`, the index
    /// of the first cell/point concerned ("" when the finding names none).
    std::string firstKind;
    std::uint64_t first = 0;
    std::string field;    ///< the field, for non_finite_field_values
    std::string action;   ///< what uvr does about it ("re-oriented for rendering")
    std::string message;  ///< the whole finding as one line
};

/// What validation found in a mesh; structural errors throw instead.
struct ValidationReport {
    std::uint64_t invertedCells = 0;     ///< re-oriented when rendering
    std::uint64_t zeroVolumeCells = 0;   ///< contribute nothing to images
    std::uint64_t distortedCells = 0;    ///< tetrahedra of both orientations
    std::uint64_t coincidentPoints = 0;  ///< points at the position of an earlier point
    std::uint64_t nonFinitePoints = 0;   ///< points with a NaN/Inf coordinate
    std::uint64_t unusedPoints = 0;      ///< points no cell references
    std::uint64_t firstInvertedCell = 0, firstZeroVolumeCell = 0, firstDistortedCell = 0;
    std::vector<NonFiniteField> nonFiniteFields;
    /// Bounds of the points of the tetrahedra rendered (those tetrahedralize keeps: finite, of
    /// non-zero volume); empty when nothing renders. Unused and NaN/Inf points lie outside it.
    Bounds3f bounds;

    /// The findings, in the order findings() lists them.
    std::vector<ValidationFinding> structuredFindings() const;
    /// Human-readable findings, one per line ("77 zero-volume cells (first: cell 1234)"); empty
    /// when the mesh is clean.
    std::vector<std::string> findings() const;
};

/// Checks the mesh's structure (offsets, corner counts, point indices in range, field sizes) and
/// throws Error(Validation) naming the first offending cell or field; then classifies every cell's
/// geometry and scans points and fields, returning the counts. `progress` hears the fraction
/// done.
ValidationReport validateMesh(const Mesh& mesh, const std::string& file = "",
                              const FractionFn& progress = {});

/// Only the structural checks of validateMesh (cheap; run by every load).
void validateStructure(const Mesh& mesh, const std::string& file = "");

/// The structural checks of the cells alone (validateStructure without the fields): at most
/// 2^32 - 1 points, cellCount + 1 offsets from 0 to the index count, each cell of a rendered
/// type with its corner count, every index below the point count. Throws Error(Validation)
/// naming the cell (Error(Unsupported) for too many points). Splitting cells (splitCell,
/// tetrahedralize) may read out of bounds on a view that fails these checks.
void validateCells(const MeshView& mesh, const std::string& file = "");

}  // namespace uvr
