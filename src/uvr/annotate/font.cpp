// SPDX-License-Identifier: MIT
// Text with FreeType (glyph outlines rasterised with anti-aliasing) and fontconfig (finding a
// system font), both opened at run time (SharedLibrary: only their headers are needed to build,
// and a binary carried to a machine without them still starts); font_none.cpp stands in when the
// build has neither.
#include "uvr/annotate/font.h"

#include <fontconfig/fontconfig.h>
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include "uvr/annotate/shared_library.h"
#include "uvr/core/error.h"
#include "uvr/core/text.h"

namespace uvr {

namespace {

// The functions used, each bound by the name of its declaration in the library's header.
#define UVR_BIND(f) decltype(&::f) f = lib.function<std::remove_pointer_t<decltype(&::f)>>(#f);

/// FreeType's functions, loaded on first use (a failure is retried at the next use).
struct FreeTypeApi {
    SharedLibrary lib{"libfreetype.so.6", "libfreetype6"};
    UVR_BIND(FT_Init_FreeType)
    UVR_BIND(FT_Done_FreeType)
    UVR_BIND(FT_New_Face)
    UVR_BIND(FT_Done_Face)
    UVR_BIND(FT_Select_Charmap)
    UVR_BIND(FT_Set_Char_Size)
    UVR_BIND(FT_Get_Char_Index)
    UVR_BIND(FT_Get_Kerning)
    UVR_BIND(FT_Load_Glyph)
};

/// fontconfig's functions, loaded on first use.
struct FontconfigApi {
    SharedLibrary lib{"libfontconfig.so.1", "libfontconfig1"};
    UVR_BIND(FcInitLoadConfigAndFonts)
    UVR_BIND(FcConfigDestroy)
    UVR_BIND(FcNameParse)
    UVR_BIND(FcPatternAddBool)
    UVR_BIND(FcConfigSubstitute)
    UVR_BIND(FcDefaultSubstitute)
    UVR_BIND(FcFontMatch)
    UVR_BIND(FcPatternGetString)
    UVR_BIND(FcPatternGetBool)
    UVR_BIND(FcPatternDestroy)
};

#undef UVR_BIND

const FreeTypeApi& freetype() {
    static const FreeTypeApi api;
    return api;
}

const FontconfigApi& fontconfig() {
    static const FontconfigApi api;
    return api;
}

}  // namespace

bool textEngineAvailable() {
    return true;
}

std::string findFontFile(const std::string& pattern) {
    const std::string missing = "no scalable font found through fontconfig for '" +
                                printableShort(pattern) +
                                "': install the Debian package fonts-dejavu-core (DejaVu Sans)";
    const FontconfigApi& fc = fontconfig();
    // A configuration of its own (not the process-wide one FcInit keeps), freed again.
    FcConfig* config = fc.FcInitLoadConfigAndFonts();
    if (!config)
        throwError(ErrorKind::Unsupported, "", missing + " (fontconfig has no configuration)");
    std::string file;
    FcPattern* pat = fc.FcNameParse(reinterpret_cast<const FcChar8*>(pattern.c_str()));
    if (pat) {
        fc.FcPatternAddBool(pat, FC_SCALABLE, FcTrue);
        fc.FcConfigSubstitute(config, pat, FcMatchPattern);
        fc.FcDefaultSubstitute(pat);
        FcResult result = FcResultNoMatch;
        FcPattern* match = fc.FcFontMatch(config, pat, &result);
        if (match) {
            FcChar8* path = nullptr;
            FcBool scalable = FcFalse;
            if (fc.FcPatternGetString(match, FC_FILE, 0, &path) == FcResultMatch && path &&
                fc.FcPatternGetBool(match, FC_SCALABLE, 0, &scalable) == FcResultMatch && scalable)
                file = reinterpret_cast<const char*>(path);
            fc.FcPatternDestroy(match);
        }
        fc.FcPatternDestroy(pat);
    }
    fc.FcConfigDestroy(config);
    if (file.empty()) throwError(ErrorKind::Unsupported, "", missing);
    return file;
}

namespace {

constexpr float kMinPixelSize = 1.f, kMaxPixelSize = 2048.f;

/// The code point drawn for `cp`: control characters (C0, DEL, C1), which have no glyph and
/// could move nothing sensibly on one line, become U+FFFD.
char32_t drawable(char32_t cp) {
    if (cp < 0x20 || (cp >= 0x7F && cp <= 0x9F)) return U'\uFFFD';
    return cp;
}

}  // namespace

struct Font::Impl {
    const FreeTypeApi& ft = freetype();  // throws when FreeType cannot be loaded
    std::string path;
    FT_Library library = nullptr;
    FT_Face face = nullptr;
    float size = 0.f;  // the pixel size set on the face

    ~Impl() {
        if (face) ft.FT_Done_Face(face);
        if (library) ft.FT_Done_FreeType(library);
    }

    void setSize(float pixelSize) {
        if (!(pixelSize >= kMinPixelSize && pixelSize <= kMaxPixelSize))
            throwError(ErrorKind::Argument, path,
                       "text size " + std::to_string(pixelSize) + " px: expected 1 to 2048");
        if (pixelSize == size) return;
        // 26.6 fixed point at 72 dpi: one point is one pixel.
        if (ft.FT_Set_Char_Size(face, 0, static_cast<FT_F26Dot6>(std::lround(pixelSize * 64.f)), 72,
                                72))
            throwError(ErrorKind::Io, path,
                       "FreeType cannot scale the font to " + std::to_string(pixelSize) + " px");
        size = pixelSize;
    }

    FT_UInt glyphIndex(char32_t cp) const {
        FT_UInt g = ft.FT_Get_Char_Index(face, drawable(cp));
        if (g == 0) g = ft.FT_Get_Char_Index(face, 0xFFFD);  // else 0: the face's .notdef box
        return g;
    }

    /// Lays out `text` glyph by glyph: calls visit(slot, penX) with each loaded (and, when
    /// render, rasterised) glyph and its pen position in pixels; returns the advance in pixels.
    template <typename Visit>
    int layout(std::string_view text, float pixelSize, bool render, Visit&& visit) {
        setSize(pixelSize);
        const bool kern = FT_HAS_KERNING(face);
        FT_Pos pen = 0;  // 26.6
        FT_UInt previous = 0;
        const FT_Int32 flags = FT_LOAD_TARGET_LIGHT | (render ? FT_LOAD_RENDER : 0);
        for (char32_t cp : decodeUtf8Lossy(text)) {
            const FT_UInt g = glyphIndex(cp);
            if (kern && previous && g) {
                FT_Vector delta{0, 0};
                if (ft.FT_Get_Kerning(face, previous, g, FT_KERNING_DEFAULT, &delta) == 0)
                    pen += delta.x;
            }
            if (ft.FT_Load_Glyph(face, g, flags) != 0) {  // a broken glyph: skip it
                previous = 0;
                continue;
            }
            visit(face->glyph, static_cast<int>((pen + 32) >> 6));
            pen += face->glyph->advance.x;
            previous = g;
        }
        return static_cast<int>((pen + 32) >> 6);
    }
};

Font::Font(const std::string& path) : impl_(std::make_unique<Impl>()) {
    impl_->path = path;
    if (impl_->ft.FT_Init_FreeType(&impl_->library) != 0)
        throwError(ErrorKind::Internal, path, "FreeType failed to initialise");
    if (impl_->ft.FT_New_Face(impl_->library, path.c_str(), 0, &impl_->face) != 0)
        throwError(ErrorKind::Io, path, "FreeType cannot open this file as a font");
    if (!FT_IS_SCALABLE(impl_->face))
        throwError(ErrorKind::Unsupported, path, "not a scalable (outline) font");
    impl_->ft.FT_Select_Charmap(impl_->face, FT_ENCODING_UNICODE);
}

Font::~Font() = default;
Font::Font(Font&&) noexcept = default;
Font& Font::operator=(Font&&) noexcept = default;

const std::string& Font::path() const {
    return impl_->path;
}

std::string Font::familyName() const {
    return impl_->face->family_name ? impl_->face->family_name : "";
}

FontMetrics Font::metrics(float pixelSize) const {
    impl_->setSize(pixelSize);
    const FT_Size_Metrics& m = impl_->face->size->metrics;
    return {m.ascender / 64.f, -m.descender / 64.f, m.height / 64.f};
}

int Font::advance(std::string_view text, float pixelSize) const {
    return impl_->layout(text, pixelSize, false, [](FT_GlyphSlot, int) {});
}

TextBox Font::inkBox(std::string_view text, float pixelSize) const {
    TextBox box{0, 0, 0, 0};
    bool any = false;
    impl_->layout(text, pixelSize, true, [&](FT_GlyphSlot slot, int penX) {
        const FT_Bitmap& bm = slot->bitmap;
        for (unsigned r = 0; r < bm.rows; ++r)
            for (unsigned c = 0; c < bm.width; ++c) {
                if (bm.buffer[static_cast<int>(r) * bm.pitch + static_cast<int>(c)] == 0) continue;
                const int x = penX + slot->bitmap_left + static_cast<int>(c);
                const int y = static_cast<int>(r) - slot->bitmap_top;
                if (!any) box = {x, y, x + 1, y + 1};
                box.x0 = std::min(box.x0, x), box.x1 = std::max(box.x1, x + 1);
                box.y0 = std::min(box.y0, y), box.y1 = std::max(box.y1, y + 1);
                any = true;
            }
    });
    return box;
}

int Font::draw(Image& image, std::string_view text, float pixelSize, int x, int baseline,
               Vec3f color, float opacity) const {
    return impl_->layout(text, pixelSize, true, [&](FT_GlyphSlot slot, int penX) {
        const FT_Bitmap& bm = slot->bitmap;
        if (bm.pixel_mode != FT_PIXEL_MODE_GRAY) return;  // outlines always render to grey
        const int left = x + penX + slot->bitmap_left, top = baseline - slot->bitmap_top;
        for (unsigned r = 0; r < bm.rows; ++r)
            for (unsigned c = 0; c < bm.width; ++c) {
                const unsigned char coverage =
                    bm.buffer[static_cast<int>(r) * bm.pitch + static_cast<int>(c)];
                if (coverage)
                    blendOver(image, left + static_cast<int>(c), top + static_cast<int>(r), color,
                              opacity * (coverage / 255.f));
            }
    });
}

}  // namespace uvr
