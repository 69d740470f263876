// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "uvr/mesh/mesh.h"

namespace uvr {

/// Which field to render: "NAME[:point|:cell][:magnitude|:x|:y|:z|:N]"; an empty name means the
/// default (defaultFieldIndex). A name that exists as point and cell data means the point data,
/// as ParaView prefers it; ":cell" selects the other.
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
    /// How the field was chosen when the spec did not say everything, for the log: "the
    /// default: ..." or "point data; pressure:cell selects the cell data" ("" otherwise).
    std::string choice = {};

    /// "pressure (point data)", for messages, logs and statistics.
    std::string describe() const;
};

/// What choosing the default field needs to know of a field (a .uvrm header has it without
/// reading any values).
struct FieldInfo {
    std::string name;
    Association association = Association::Point;
    int components = 1;
    /// Known to hold one value (NaN left out) or none: it would render as nothing or one colour,
    /// so it is the default only when every other field is too (false when values are unknown).
    bool constant = false;
};

/// True for the names of id and bookkeeping arrays that writers add beside physical fields
/// (GlobalNodeId, GlobalElementId, PedigreeIds, vtkOriginalCellIds, ObjectId, vtkGhostType, ...):
/// a name ending in "Id", "ID", "Ids", "IDs", "_id" or "_ids", or a VTK ghost/mask array. Such a
/// field is rendered when named, never chosen as the default while a physical field exists.
bool isIdFieldName(const std::string& name);

/// The field rendered when --field is not given, the same whatever the file format lists first
/// (ParaView's preference): the first point-data scalar field, else the first cell-data scalar
/// field, else the first point-data vector (its magnitude), else the first cell-data vector; id
/// arrays (isIdFieldName) only when no other field exists, constant fields (FieldInfo::constant)
/// only when no other physical field exists. Empty for no fields.
std::optional<std::size_t> defaultFieldIndex(const std::vector<FieldInfo>& fields);
/// The same for a mesh's fields (their values tell which are constant: fieldInfos).
std::optional<std::size_t> defaultFieldIndex(const Mesh& mesh);

/// What choosing a field needs to know of a mesh's fields, constancy included.
std::vector<FieldInfo> fieldInfos(const Mesh& mesh);

/// The field a spec names among `fields` (its index) and, when the spec left something to
/// choose, how it was chosen (ScalarField::choice).
struct FieldChoice {
    std::size_t index = 0;
    std::string choice;
};

/// Resolves a spec against a list of fields (a mesh's, or a .uvrm header's before its values are
/// read); throws Error(Argument) as selectScalarField does.
FieldChoice resolveField(const std::vector<FieldInfo>& fields, const FieldSpec& spec);

/// The spec with the field it resolves to on `mesh` named (name and association), component as
/// given: what a time series renders at every step, so that the default chosen at its first step
/// (which passes over fields constant there) stays the field of every step. Throws as
/// resolveField does.
FieldSpec pinField(const Mesh& mesh, const FieldSpec& spec);

/// Resolves a spec against the mesh and extracts the scalar values; throws Error(Argument) naming
/// the available fields when the name, association or component does not exist, or when a name
/// exists as both point and cell data and the spec does not say which.
ScalarField selectScalarField(const Mesh& mesh, const FieldSpec& spec);

/// The scalar values of one field of the mesh: component `component`, or for component -1 the
/// magnitude of a vector (the value itself for scalars); throws Error(Argument) when the component
/// does not exist. Unlike selectScalarField it does not look the field up by name.
ScalarField scalarFieldOf(const MeshView& mesh, const Field& field, int component = -1);

/// Finite minimum and maximum of values (NaN/Inf skipped); {0, 0} when none is finite.
std::pair<float, float> finiteRange(const std::vector<float>& values);

}  // namespace uvr
