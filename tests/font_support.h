// SPDX-License-Identifier: MIT
#pragma once
// The font the text tests draw with (tests only).

#include <gtest/gtest.h>

#include <memory>

#include "uvr/annotate/font.h"

namespace uvr::testing {

/// The system's default font (DejaVu Sans), loaded once; null when this build has no text.
inline const Font* systemFont() {
    static const std::unique_ptr<Font> font =
        textEngineAvailable() ? std::make_unique<Font>(findFontFile()) : nullptr;
    return font.get();
}

}  // namespace uvr::testing

/// Declares `font` (the system font), or skips the test where this build has no text.
#define UVR_REQUIRE_FONT()                                                    \
    const ::uvr::Font* fontPtr = ::uvr::testing::systemFont();                \
    if (!fontPtr) GTEST_SKIP() << "built without text (UVR_ENABLE_TEXT=OFF)"; \
    const ::uvr::Font& font = *fontPtr
