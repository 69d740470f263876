// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtk_number.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace uvr {
namespace {

TEST(VtkNumber, IntegersTakeSignsSpacesAndIntegralRealForms) {
    EXPECT_EQ(parseVtkInteger("11047"), 11047);
    EXPECT_EQ(parseVtkInteger("+11047"), 11047);  // a lattice-Boltzmann code's NumberOfPoints
    EXPECT_EQ(parseVtkInteger("  -3\t\n"), -3);
    EXPECT_EQ(parseVtkInteger("007"), 7);  // decimal, not octal, as C++ streams read it
    EXPECT_EQ(parseVtkInteger("4.0"), 4);
    EXPECT_EQ(parseVtkInteger("1e3"), 1000);
    EXPECT_EQ(parseVtkInteger("1E+03"), 1000);
    EXPECT_EQ(parseVtkInteger("-2.5e1"), -25);
    EXPECT_EQ(parseVtkInteger("9223372036854775807"), std::numeric_limits<std::int64_t>::max());
    EXPECT_EQ(parseVtkInteger("-9223372036854775808"), std::numeric_limits<std::int64_t>::min());
}

TEST(VtkNumber, IntegersRefuseWhatVtkMisreads) {
    for (const char* bad : {"", " ", "+", "-", "+-1", "++1", "4abc", "0x10", "1.5", "1e-1", "nan",
                            "inf", "1.5d0", "1,5", "9223372036854775808", "1e30", "4 5", "e3", "."})
        EXPECT_FALSE(parseVtkInteger(bad).has_value()) << "'" << bad << "'";
}

TEST(VtkNumber, CountsAreNonNegative) {
    EXPECT_EQ(parseVtkCount("+11047"), 11047u);
    EXPECT_EQ(parseVtkCount(" 18446744073709551615 "), std::numeric_limits<std::uint64_t>::max());
    EXPECT_EQ(parseVtkCount("-0"), 0u);
    EXPECT_EQ(parseVtkCount("2e2"), 200u);
    for (const char* bad : {"-1", "18446744073709551616", "0x4", "4abc", "", "-1e2", "+-0"})
        EXPECT_FALSE(parseVtkCount(bad).has_value()) << "'" << bad << "'";
}

TEST(VtkNumber, RealsTakeExponentsSignsAndNonFiniteWords) {
    EXPECT_EQ(parseVtkReal("+1.5"), 1.5);
    EXPECT_EQ(parseVtkReal("1e3"), 1000.0);
    EXPECT_EQ(parseVtkReal("1E+03"), 1000.0);
    EXPECT_EQ(parseVtkReal("2.5e-1"), 0.25);
    EXPECT_EQ(parseVtkReal(".5"), 0.5);
    EXPECT_EQ(parseVtkReal("5."), 5.0);
    EXPECT_EQ(parseVtkReal(" \t-7 \r\n"), -7.0);
    EXPECT_TRUE(std::isnan(*parseVtkReal("nan")));
    EXPECT_TRUE(std::isnan(*parseVtkReal("+nan")));
    EXPECT_TRUE(std::isnan(*parseVtkReal("NaN")));
    EXPECT_EQ(*parseVtkReal("inf"), std::numeric_limits<double>::infinity());
    EXPECT_EQ(*parseVtkReal("-inf"), -std::numeric_limits<double>::infinity());
    EXPECT_EQ(*parseVtkReal("-Infinity"), -std::numeric_limits<double>::infinity());
    EXPECT_EQ(*parseVtkReal("1e400"), std::numeric_limits<double>::infinity());
    EXPECT_EQ(*parseVtkReal("1e-400"), 0.0);
}

TEST(VtkNumber, RealsRefuseGarbage) {
    for (const char* bad :
         {"", "+", "-", "+-1", "1.5d0", "0x10", "1,5", "1f", "1e", "1e+", "--1", "nanx", "1 2"})
        EXPECT_FALSE(parseVtkReal(bad).has_value()) << "'" << bad << "'";
}

}  // namespace
}  // namespace uvr
