// SPDX-License-Identifier: MIT
#include "uvr/mesh/field_select.h"

#include <gtest/gtest.h>

#include <cmath>

#include "uvr/core/error.h"

namespace uvr {
namespace {

Mesh meshWithFields() {
    Mesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const std::uint32_t ids[4] = {0, 1, 2, 3};
    m.addCell(CellType::Tetra, ids);
    m.fields.push_back({"v", Association::Point, 3, {3, 4, 0, 0, 0, 0, 1, 2, 2, NAN, 0, 0}});
    m.fields.push_back({"p", Association::Point, 1, {1, 2, 3, 4}});
    m.fields.push_back({"p", Association::Cell, 1, {7}});
    return m;
}

TEST(FieldSelect, DefaultIsFirstScalarField) {
    const ScalarField f = selectScalarField(meshWithFields(), parseFieldSpec(""));
    EXPECT_EQ(f.name, "p");
    EXPECT_EQ(f.association, Association::Point);
    EXPECT_EQ(f.values, (std::vector<float>{1, 2, 3, 4}));
}

TEST(FieldSelect, VectorMagnitudeAndComponents) {
    const Mesh m = meshWithFields();
    const ScalarField mag = selectScalarField(m, parseFieldSpec("v"));
    EXPECT_FLOAT_EQ(mag.values[0], 5.f);
    EXPECT_FLOAT_EQ(mag.values[2], 3.f);
    EXPECT_TRUE(std::isnan(mag.values[3]));
    const ScalarField y = selectScalarField(m, parseFieldSpec("v:point:y"));
    EXPECT_EQ(y.values, (std::vector<float>{4, 0, 2, 0}));
    EXPECT_EQ(selectScalarField(m, parseFieldSpec("v:2")).values[2], 2.f);
    EXPECT_EQ(finiteRange(mag.values), (std::pair<float, float>{0.f, 5.f}));
}

TEST(FieldSelect, ANameOfPointAndCellDataMeansThePointData) {
    const Mesh m = meshWithFields();
    EXPECT_EQ(selectScalarField(m, parseFieldSpec("p:cell")).values, std::vector<float>{7});
    EXPECT_EQ(selectScalarField(m, parseFieldSpec("p:point")).values.size(), 4u);
    EXPECT_EQ(selectScalarField(m, parseFieldSpec("p:point")).choice, "");
    const ScalarField p = selectScalarField(m, parseFieldSpec("p"));
    EXPECT_EQ(p.association, Association::Point);
    EXPECT_EQ(p.values, (std::vector<float>{1, 2, 3, 4}));
    EXPECT_NE(p.choice.find("`field` p:cell"), std::string::npos) << p.choice;
    EXPECT_EQ(p.describe(), "p (point data)");
}

TEST(FieldSelect, IdArrayNames) {
    for (const char* id : {"GlobalNodeId", "GlobalElementId", "PedigreeIds", "vtkOriginalCellIds",
                           "vtkOriginalPointIds", "ObjectId", "BlockId", "ElementID", "node_id",
                           "cell_ids", "vtkGhostType", "vtkValidPointMask", "vtkProcessId"})
        EXPECT_TRUE(isIdFieldName(id)) << id;
    for (const char* physical : {"fluid", "void", "Id", "pressure", "VEL", "Acid", "rigid",
                                 "temperature_idx", "density", "EQPS"})
        EXPECT_FALSE(isIdFieldName(physical)) << physical;
}

TEST(FieldSelect, DefaultPrefersPhysicalPointScalarsWhateverTheOrder) {
    using A = Association;
    auto pick = [](std::vector<FieldInfo> f) {
        const auto i = defaultFieldIndex(f);
        return i ? f[*i].name : std::string("none");
    };
    EXPECT_EQ(pick({}), "none");
    // Cell data listed first (as legacy VTK files write it) does not win over point data.
    EXPECT_EQ(pick({{"pressure", A::Cell, 1}, {"pressure", A::Point, 1}}), "pressure");
    EXPECT_EQ(defaultFieldIndex(std::vector<FieldInfo>{{"p", A::Cell, 1}, {"p", A::Point, 1}}),
              std::optional<std::size_t>(1));
    EXPECT_EQ(pick({{"GlobalNodeId", A::Point, 1}, {"EQPS", A::Cell, 1}, {"VEL", A::Point, 3}}),
              "EQPS");
    EXPECT_EQ(pick({{"GlobalNodeId", A::Point, 1}, {"VEL", A::Point, 3}, {"s", A::Cell, 3}}),
              "VEL");
    EXPECT_EQ(pick({{"v", A::Cell, 3}, {"w", A::Point, 3}}), "w");
    EXPECT_EQ(pick({{"GlobalElementId", A::Cell, 1}, {"GlobalNodeId", A::Point, 1}}),
              "GlobalNodeId");
    EXPECT_EQ(pick({{"a", A::Point, 1}, {"b", A::Point, 1}}), "a");
}

TEST(FieldSelect, DefaultSaysWhyAndKeepsAnAssociation) {
    Mesh m = meshWithFields();
    m.fields.insert(m.fields.begin(), Field{"GlobalNodeId", Association::Point, 1, {0, 1, 2, 3}});
    m.fields.insert(m.fields.begin(), Field{"c", Association::Cell, 1, {9}});
    const ScalarField d = selectScalarField(m, parseFieldSpec(""));
    EXPECT_EQ(d.describe(), "p (point data)");
    EXPECT_NE(d.choice.find("the default"), std::string::npos) << d.choice;
    EXPECT_EQ(selectScalarField(m, parseFieldSpec(":cell")).describe(), "c (cell data)");
    EXPECT_EQ(selectScalarField(m, parseFieldSpec("GlobalNodeId")).values.size(), 4u);
}

TEST(FieldSelect, DefaultPassesOverConstantFieldsAndSaysSo) {
    // Issue 35: VTK's mug.e, whose first field holds one value at step 0, rendered empty.
    Mesh m = meshWithFields();
    m.fields.insert(m.fields.begin(), Field{"zero", Association::Point, 1, {0, 0, NAN, 0}});
    m.fields.insert(m.fields.begin(), Field{"NodeId", Association::Point, 1, {0, 1, 2, 3}});
    const ScalarField d = selectScalarField(m, parseFieldSpec(""));
    EXPECT_EQ(d.describe(), "p (point data)");
    EXPECT_NE(d.choice.find("that is not constant (zero holds one value here)"), std::string::npos)
        << d.choice;
    const std::vector<FieldInfo> infos = fieldInfos(m);
    EXPECT_TRUE(infos[1].constant);   // zero: NaN left out
    EXPECT_FALSE(infos[2].constant);  // v: its components vary
    EXPECT_EQ(pinField(m, parseFieldSpec("")).name, "p");
    EXPECT_EQ(pinField(m, parseFieldSpec("zero")).name, "zero");  // named: as given
    // Every physical field constant: the first of them, before the id array.
    Mesh flat;
    flat.points = m.points;
    flat.addCell(CellType::Tetra, std::vector<std::uint32_t>{0, 1, 2, 3});
    flat.fields = {{"NodeId", Association::Point, 1, {0, 1, 2, 3}},
                   {"a", Association::Point, 1, {2, 2, 2, 2}},
                   {"b", Association::Point, 1, {5, 5, 5, 5}}};
    const ScalarField f = selectScalarField(flat, parseFieldSpec(""));
    EXPECT_EQ(f.name, "a");
    EXPECT_EQ(f.choice.find("not constant"), std::string::npos) << f.choice;
}

TEST(FieldSelect, TwoPointFieldsOfTheSameNameAreNotCalledPointAndCell) {
    Mesh m = meshWithFields();
    m.fields.push_back({"p", Association::Point, 1, {5, 6, 7, 8}});
    for (const char* spec : {"p", "p:point"}) {
        try {
            selectScalarField(m, parseFieldSpec(spec));
            FAIL() << spec;
        } catch (const Error& e) {
            EXPECT_EQ(e.kind(), ErrorKind::Argument);
            const std::string what = e.what();
            EXPECT_NE(what.find("cannot tell them apart"), std::string::npos) << what;
            EXPECT_EQ(what.find("exists as point and cell"), std::string::npos) << what;
        }
    }
    EXPECT_EQ(selectScalarField(m, parseFieldSpec("p:cell")).values, std::vector<float>{7});
}

TEST(FieldSelect, UnknownNamesQualifiersAndComponentsAreArgumentErrors) {
    const Mesh m = meshWithFields();
    try {
        selectScalarField(m, parseFieldSpec("nope"));
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_NE(std::string(e.what()).find("available: v:point"), std::string::npos) << e.what();
    }
    EXPECT_THROW(parseFieldSpec("p:bogus"), Error);
    EXPECT_THROW(selectScalarField(m, parseFieldSpec("v:3")), Error);
    EXPECT_THROW(selectScalarField(m, parseFieldSpec("v:cell")), Error);
}

}  // namespace
}  // namespace uvr
