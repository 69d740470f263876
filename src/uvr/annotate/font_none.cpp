// SPDX-License-Identifier: MIT
// Stands in for font.cpp in a build without FreeType and fontconfig (UVR_ENABLE_TEXT=OFF): every
// use of text says how to get it.
#include "uvr/annotate/font.h"

#include "uvr/core/error.h"

namespace uvr {

namespace {

[[noreturn]] void noTextEngine() {
    throwError(ErrorKind::Unsupported, "",
               "this uvr was built without text (FreeType and fontconfig): install the Debian "
               "packages libfreetype-dev, libfontconfig-dev and fonts-dejavu-core, then "
               "reconfigure with -DUVR_ENABLE_TEXT=ON");
}

}  // namespace

struct Font::Impl {};

bool textEngineAvailable() {
    return false;
}
std::string findFontFile(const std::string&) {
    noTextEngine();
}
Font::Font(const std::string&) {
    noTextEngine();
}
Font::~Font() = default;
Font::Font(Font&&) noexcept = default;
Font& Font::operator=(Font&&) noexcept = default;
const std::string& Font::path() const {
    noTextEngine();
}
std::string Font::familyName() const {
    noTextEngine();
}
FontMetrics Font::metrics(float) const {
    noTextEngine();
}
int Font::advance(std::string_view, float) const {
    noTextEngine();
}
TextBox Font::inkBox(std::string_view, float) const {
    noTextEngine();
}
int Font::draw(Image&, std::string_view, float, int, int, Vec3f, float) const {
    noTextEngine();
}

}  // namespace uvr
