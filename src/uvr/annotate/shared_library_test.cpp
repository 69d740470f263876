// SPDX-License-Identifier: MIT
#include "uvr/annotate/shared_library.h"

#include <gtest/gtest.h>

#include <string>

#include "uvr/core/error.h"

namespace uvr {
namespace {

TEST(LegendSharedLibrary, AMissingLibraryOrSymbolNamesThePackage) {
    try {
        SharedLibrary lib("libuvr-no-such-library.so.7", "uvr-no-such-package");
        FAIL() << "opened";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
        const std::string m = e.what();
        EXPECT_NE(m.find("libuvr-no-such-library.so.7"), std::string::npos) << m;
        EXPECT_NE(m.find("install the Debian package uvr-no-such-package"), std::string::npos) << m;
    }
    const SharedLibrary freetype("libfreetype.so.6", "libfreetype6");
    EXPECT_NE(freetype.symbol("FT_Init_FreeType"), nullptr);
    try {
        freetype.symbol("FT_No_Such_Function");
        FAIL() << "found";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("FT_No_Such_Function"), std::string::npos);
    }
}

}  // namespace
}  // namespace uvr
