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

TEST(FieldSelect, PointAndCellOfTheSameNameNeedAQualifier) {
    const Mesh m = meshWithFields();
    EXPECT_EQ(selectScalarField(m, parseFieldSpec("p:cell")).values, std::vector<float>{7});
    EXPECT_EQ(selectScalarField(m, parseFieldSpec("p:point")).values.size(), 4u);
    try {
        selectScalarField(m, parseFieldSpec("p"));
        FAIL();
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Argument);
        EXPECT_NE(std::string(e.what()).find(":cell"), std::string::npos);
    }
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
