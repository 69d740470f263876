// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/scalar_type.h"

namespace uvr {

std::optional<ScalarType> parseLegacyTypeName(const std::string& name) {
    if (name == "bit") return std::nullopt;  // packed bits: not a numeric array uvr reads
    // The vtktype* names: VTK 9.1 knows only the 64-bit ones, meshio writes all of them.
    if (name == "char" || name == "vtktypeint8") return ScalarType::Int8;
    if (name == "signed_char") return ScalarType::Int8;
    if (name == "unsigned_char" || name == "vtktypeuint8") return ScalarType::UInt8;
    if (name == "short" || name == "vtktypeint16") return ScalarType::Int16;
    if (name == "unsigned_short" || name == "vtktypeuint16") return ScalarType::UInt16;
    if (name == "int" || name == "vtktypeint32") return ScalarType::Int32;
    if (name == "unsigned_int" || name == "vtktypeuint32") return ScalarType::UInt32;
    if (name == "long" || name == "vtktypeint64" || name == "vtkIdType" || name == "long_long")
        return ScalarType::Int64;
    if (name == "unsigned_long" || name == "vtktypeuint64" || name == "unsigned_long_long")
        return ScalarType::UInt64;
    if (name == "float" || name == "vtktypefloat32") return ScalarType::Float32;
    if (name == "double" || name == "vtktypefloat64") return ScalarType::Float64;
    return std::nullopt;
}

std::optional<ScalarType> parseXmlTypeName(const std::string& name) {
    if (name == "Int8") return ScalarType::Int8;
    if (name == "UInt8") return ScalarType::UInt8;
    if (name == "Int16") return ScalarType::Int16;
    if (name == "UInt16") return ScalarType::UInt16;
    if (name == "Int32") return ScalarType::Int32;
    if (name == "UInt32") return ScalarType::UInt32;
    if (name == "Int64") return ScalarType::Int64;
    if (name == "UInt64") return ScalarType::UInt64;
    if (name == "Float32") return ScalarType::Float32;
    if (name == "Float64") return ScalarType::Float64;
    return std::nullopt;
}

const char* xmlTypeName(ScalarType t) {
    switch (t) {
        case ScalarType::Int8:
            return "Int8";
        case ScalarType::UInt8:
            return "UInt8";
        case ScalarType::Int16:
            return "Int16";
        case ScalarType::UInt16:
            return "UInt16";
        case ScalarType::Int32:
            return "Int32";
        case ScalarType::UInt32:
            return "UInt32";
        case ScalarType::Int64:
            return "Int64";
        case ScalarType::UInt64:
            return "UInt64";
        case ScalarType::Float32:
            return "Float32";
        case ScalarType::Float64:
            return "Float64";
    }
    return "?";
}

}  // namespace uvr
