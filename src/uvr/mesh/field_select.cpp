// SPDX-License-Identifier: MIT
#include "uvr/mesh/field_select.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

#include "uvr/core/error.h"
#include "uvr/core/setting_error.h"

namespace uvr {

FieldSpec parseFieldSpec(const std::string& text) {
    FieldSpec spec;
    size_t pos = text.find(':');
    spec.name = text.substr(0, pos);
    while (pos != std::string::npos) {
        size_t next = text.find(':', pos + 1);
        std::string part =
            text.substr(pos + 1, next == std::string::npos ? std::string::npos : next - pos - 1);
        if (part == "point") {
            spec.association = Association::Point;
        } else if (part == "cell") {
            spec.association = Association::Cell;
        } else if (part == "magnitude") {
            spec.component = -1;
            spec.selectsComponent = true;
        } else if (part == "x" || part == "y" || part == "z") {
            spec.component = part[0] - 'x';
            spec.selectsComponent = true;
        } else if (!part.empty() && part.find_first_not_of("0123456789") == std::string::npos &&
                   part.size() < 6) {
            spec.component = std::stoi(part);
            spec.selectsComponent = true;
        } else {
            throw SettingError(
                "field", "'" + text + "'",
                "unknown qualifier '" + part +
                    "' (expected point, cell, magnitude, x, y, z or a component number)");
        }
        pos = next;
    }
    return spec;
}

bool isIdFieldName(const std::string& name) {
    static const char* const kExact[] = {"vtkGhostType", "vtkGhostLevels", "vtkValidPointMask",
                                         "vtkProcessId", "ProcessId"};
    for (const char* n : kExact)
        if (name == n) return true;
    auto endsWith = [&](std::string_view suffix) {
        return name.size() > suffix.size() &&
               std::string_view(name).substr(name.size() - suffix.size()) == suffix;
    };
    // Case matters: "Id" after a word ("GlobalNodeId"), not "fluid" or "void".
    return endsWith("Id") || endsWith("ID") || endsWith("Ids") || endsWith("IDs") ||
           endsWith("_id") || endsWith("_ids");
}

std::optional<std::size_t> defaultFieldIndex(const std::vector<FieldInfo>& fields) {
    for (const bool ids : {false, true})
        for (const bool constant : {false, true})
            for (const bool vectors : {false, true})
                for (const Association a : {Association::Point, Association::Cell})
                    for (std::size_t i = 0; i < fields.size(); ++i) {
                        const FieldInfo& f = fields[i];
                        if (f.association == a && (f.components > 1) == vectors &&
                            isIdFieldName(f.name) == ids && f.constant == constant)
                            return i;
                    }
    return std::nullopt;
}

std::vector<FieldInfo> fieldInfos(const Mesh& mesh) {
    std::vector<FieldInfo> infos;
    infos.reserve(mesh.fields.size());
    for (const Field& f : mesh.fields) {
        // Constant: every component holds one value over the tuples (NaN left out); a scan
        // that stops at the first pair of differing values, at once for most fields.
        bool constant = true;
        const std::size_t nc = static_cast<std::size_t>(std::max(f.components, 1));
        for (std::size_t c = 0; c < nc && constant; ++c) {
            float first = NAN;
            for (std::size_t i = c; i < f.values.size(); i += nc) {
                const float v = f.values[i];
                if (v != v) continue;
                if (first != first) {
                    first = v;
                } else if (v != first) {
                    constant = false;
                    break;
                }
            }
        }
        infos.push_back({f.name, f.association, f.components, constant});
    }
    return infos;
}

std::optional<std::size_t> defaultFieldIndex(const Mesh& mesh) {
    return defaultFieldIndex(fieldInfos(mesh));
}

std::string ScalarField::describe() const {
    return name + " (" + associationName(association) + " data)";
}

FieldChoice resolveField(const std::vector<FieldInfo>& fields, const FieldSpec& spec) {
    auto describe = [&] {
        if (fields.empty()) return std::string("the mesh has no fields");
        std::string s = "available:";
        for (const FieldInfo& f : fields)
            s += " " + f.name + ":" + associationName(f.association) +
                 (f.components > 1 ? "(" + std::to_string(f.components) + " components)" : "");
        return s;
    };
    std::optional<std::size_t> index;
    std::string choice;
    if (spec.name.empty()) {
        if (spec.association) {  // ":cell" alone: the default among the cell fields
            std::vector<FieldInfo> some;
            std::vector<std::size_t> where;
            for (std::size_t i = 0; i < fields.size(); ++i)
                if (fields[i].association == *spec.association) {
                    some.push_back(fields[i]);
                    where.push_back(i);
                }
            if (const auto i = defaultFieldIndex(some)) index = where[*i];
        } else {
            index = defaultFieldIndex(fields);
        }
        if (!index) throwError(ErrorKind::Argument, "", "no field to render: " + describe());
        const FieldInfo& f = fields[*index];
        // A constant field the choice passed over, to say so.
        std::string skipped;
        for (const FieldInfo& g : fields)
            if (g.constant && !f.constant && !isIdFieldName(g.name) && skipped.empty())
                skipped = g.name;
        choice = isIdFieldName(f.name)
                     ? "the default: the file holds only id arrays"
                     : std::string("the default: the first ") + associationName(f.association) +
                           (f.components == 1 ? "-data scalar field"
                                              : "-data field (no scalar field exists)") +
                           (skipped.empty()
                                ? ""
                                : " that is not constant (" + skipped + " holds one value here)");
    } else {
        int matches = 0, pointMatches = 0;
        for (std::size_t i = 0; i < fields.size(); ++i) {
            const FieldInfo& f = fields[i];
            if (f.name != spec.name) continue;
            if (spec.association && f.association != *spec.association) continue;
            if (!index) index = i;
            ++matches;
            pointMatches += f.association == Association::Point;
        }
        if (!index)
            throw SettingError(
                "field",
                "'" + spec.name +
                    (spec.association ? std::string(":") + associationName(*spec.association)
                                      : "") +
                    "'",
                "not found; " + describe());
        if (matches == 2 && pointMatches == 1) {
            // The name exists as point and cell data: the point data, as ParaView prefers it.
            for (std::size_t i = 0; i < fields.size(); ++i)
                if (fields[i].name == spec.name && fields[i].association == Association::Point)
                    index = i;
            choice = "point data; the file also has cell data of this name: `field` " + spec.name +
                     ":cell selects it";
        } else if (matches > 1) {
            const int cellMatches = matches - pointMatches;
            const std::string points = std::to_string(pointMatches) + " point";
            const std::string cells = std::to_string(cellMatches) + " cell";
            throw SettingError(
                "field", "'" + spec.name + "'",
                (cellMatches == 0    ? points
                 : pointMatches == 0 ? cells
                                     : points + " and " + cells) +
                    " fields have this name and a field spec cannot tell them apart; rename "
                    "them in the file");
        }
    }
    if (spec.selectsComponent && fields[*index].components == 1)
        throw SettingError("field", "'" + spec.name + "'",
                           "a scalar field; :x, :y, :z, :magnitude and a "
                           "component number select from vector fields (leave the qualifier out)");
    if (spec.component >= fields[*index].components)
        throw SettingError("field", "'" + fields[*index].name + "'",
                           "component " + std::to_string(spec.component) +
                               " does not exist (the field has " +
                               std::to_string(fields[*index].components) + ")");
    return {*index, std::move(choice)};
}

FieldSpec pinField(const Mesh& mesh, const FieldSpec& spec) {
    if (!spec.name.empty()) return spec;
    const FieldChoice choice = resolveField(fieldInfos(mesh), spec);
    FieldSpec pinned = spec;
    pinned.name = mesh.fields[choice.index].name;
    pinned.association = mesh.fields[choice.index].association;
    return pinned;
}

ScalarField selectScalarField(const Mesh& mesh, const FieldSpec& spec) {
    FieldChoice choice = resolveField(spec.name.empty() ? fieldInfos(mesh) : [&] {
        std::vector<FieldInfo> infos;  // a named field: no need to scan the values
        for (const Field& f : mesh.fields) infos.push_back({f.name, f.association, f.components});
        return infos;
    }(), spec);
    ScalarField out = scalarFieldOf(mesh, mesh.fields[choice.index], spec.component);
    out.choice = std::move(choice.choice);
    return out;
}

ScalarField scalarFieldOf(const MeshView& mesh, const Field& fieldRef, int component) {
    const Field* field = &fieldRef;
    const std::uint64_t tuples =
        field->association == Association::Point ? mesh.pointCount() : mesh.cellCount();
    UVR_CHECK(field->tupleCount() == tuples && field->values.size() == tuples * field->components,
              "field '" << field->name << "' holds " << field->values.size() << " values for "
                        << tuples << " tuples");
    if (component >= field->components)
        throw SettingError("field", "'" + field->name + "'",
                           "component " + std::to_string(component) +
                               " does not exist (the field has " +
                               std::to_string(field->components) + ")");
    ScalarField out;
    out.name = field->name;
    out.association = field->association;
    const int nc = field->components;
    if (nc == 1) {
        out.values = field->values;
        return out;
    }
    out.values.resize(tuples);
    if (component >= 0) {
        out.name += ":" + std::to_string(component);
        for (std::uint64_t i = 0; i < tuples; ++i)
            out.values[i] = field->values[i * nc + component];
    } else {
        out.name += ":magnitude";
        for (std::uint64_t i = 0; i < tuples; ++i) {
            double s = 0;
            for (int c = 0; c < nc; ++c) {
                double v = field->values[i * nc + c];
                s += v * v;
            }
            out.values[i] = static_cast<float>(std::sqrt(s));
        }
    }
    return out;
}

std::pair<float, float> finiteRange(const std::vector<float>& values) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (float v : values)
        if (std::isfinite(v)) {
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
    if (lo > hi) return {0.f, 0.f};
    return {lo, hi};
}

}  // namespace uvr
