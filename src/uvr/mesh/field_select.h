// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "uvr/mesh/mesh.h"

namespace uvr {

/// Which field to render: "NAME[:point|:cell][:magnitude|:x|:y|:z|:N]"; an empty name means the
/// default (the first field with one component, else the first field's magnitude).
struct FieldSpec {
    std::string name;
    std::optional<Association> association;
    int component = -1;  ///< -1: magnitude for vectors (the value itself for scalars)
    /// A component or :magnitude was named (refused for a scalar field: nothing to select).
    bool selectsComponent = false;
};

/// Parses a field spec; throws Error(Argument) on an unknown suffix.
FieldSpec parseFieldSpec(const std::string& text);

/// A scalar field ready for rendering: one value per point or per cell of the mesh.
struct ScalarField {
    std::string name;  ///< the field's name plus its component suffix when one was chosen
    Association association = Association::Point;
    std::vector<float> values;
};

/// Resolves a spec against the mesh and extracts the scalar values; throws Error(Argument) naming
/// the available fields when the name, association or component does not exist, or when a name
/// exists as both point and cell data and the spec does not say which.
ScalarField selectScalarField(const Mesh& mesh, const FieldSpec& spec);

/// The scalar values of one field of the mesh: component `component`, or for component -1 the
/// magnitude of a vector (the value itself for scalars); throws Error(Argument) when the component
/// does not exist. Unlike selectScalarField it does not look the field up by name.
ScalarField scalarFieldOf(const Mesh& mesh, const Field& field, int component = -1);

/// Finite minimum and maximum of values (NaN/Inf skipped); {0, 0} when none is finite.
std::pair<float, float> finiteRange(const std::vector<float>& values);

}  // namespace uvr
