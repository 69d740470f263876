// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "uvr/annotate/font.h"
#include "uvr/core/vec.h"
#include "uvr/mesh/mesh.h"
#include "uvr/render/camera.h"
#include "uvr/render/frame_setup.h"
#include "uvr/render/image.h"
#include "uvr/tf/transfer_function.h"

namespace uvr {

/// The values a colour legend marks and their labels.
struct LegendTicks {
    std::vector<double> values;       ///< ascending, within [lo, hi]
    std::vector<std::string> labels;  ///< one per value, UTF-8
};

/// "Nice" tick values within [lo, hi]. Linear: multiples of a step 1, 2 or 5 times a power of
/// ten, the step whose tick count is closest to `target` within [2, maxCount] (the more ticks on
/// a tie); log: the decades 10^k when there are 3 or more (every n-th when more than maxCount),
/// else the 1-2-5 multiples of powers of ten, else the two decades, else linear ticks. lo == hi
/// gives that one value. Throws
/// Error(Argument) for a non-finite lo or hi, lo > hi, maxCount < 2, or a log scale with lo <= 0.
LegendTicks legendTicks(double lo, double hi, bool logScale, int target = 5, int maxCount = 8);

/// Labels for tick values in one format that stays short from 1e-30 to 1e30: fixed point with
/// the fewest decimals that give every value (the same for all) when the largest magnitude lies
/// in [1e-3, 1e5) ("0.0", "0.5", "1.0"), else scientific with a common mantissa precision
/// ("1.0e-30", "1.5e-30"; a zero among them "0"), as ParaView's and matplotlib's labels keep one
/// precision; negative numbers get the minus sign U+2212. With logScale each label takes its own
/// shortest form: fixed point when all values lie in [1e-3, 1e5), else 10 with a superscript
/// exponent ("10⁶", "2×10⁻⁷").
std::vector<std::string> formatTickLabels(const std::vector<double>& values, bool logScale = false);

/// ParaView's range labels: the ends lo and hi join `ticks` (4 significant digits) unless a tick
/// already marks them, and the ticks closer to an end than `gap` (a fraction of the bar) leave,
/// so that no two labels overlap.
void addRangeEnds(LegendTicks& ticks, double lo, double hi, bool logScale, double gap);

/// Position in [0, 1] of value v along a legend of [lo, hi] (log: of log10 v), clamped; 0.5 when
/// lo == hi. The transfer function's colour at that position is the colour of v.
double legendPosition(double v, double lo, double hi, bool logScale);

/// Which edge of the image the legend stands at (vertically centred).
enum class LegendPosition { Right, Left };

/// How a legend looks beyond its content.
struct LegendStyle {
    LegendPosition position = LegendPosition::Right;
    /// The colour the image will be composited over (--background), or none for a transparent
    /// image: the legend's backing box takes this colour (white when none), the text and frame
    /// the one of black and white that contrasts with it.
    std::optional<Vec3f> background;
};

/// A pixel rectangle [x0, x1) x [y0, y1) of an image.
struct PixelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

/// Where drawLegend put its parts, in image pixels.
struct LegendLayout {
    float fontSize = 0.f;  ///< the tick labels' pixel size; the title's is 1.15 times it
    PixelRect box;         ///< the semi-transparent backing box around everything
    PixelRect bar;         ///< the colour gradient: top row the transfer function at 1, bottom at 0
    PixelRect title;       ///< the pen box of the title line
    LegendTicks ticks;
    std::vector<int> tickRows;  ///< the row of each tick mark
    /// The columns at its edge the legend keeps for itself: from the edge to the box and its
    /// margin again beyond it, at most a third of the width (a long title's box may be
    /// wider). A reset camera keeps the volume off them (clearColumns).
    int columns = 0;
};

/// A legend's title: the field's name and whether it is point or cell data ("density (point)").
inline std::string legendTitle(const std::string& field, Association association) {
    return field + " (" + associationName(association) + ")";
}

/// The smallest image a legend is drawn on (its text would not be readable on less).
inline constexpr int kLegendMinWidth = 128;
inline constexpr int kLegendMinHeight = 128;

/// Draws a colour legend in the style of ParaView's scalar bar onto a premultiplied image: a
/// vertical bar with the transfer function's colours over its normalised domain (colour only, as
/// ParaView and matplotlib show it: opacity per unit length is not what the image shows), the
/// title above it and ticks from legendTicks(lo, hi, logScale) and the range's ends
/// (addRangeEnds) beside it, all on an opaque-text,
/// semi-transparent box so it reads over the rendering and on a transparent PNG. Its size scales
/// with the image (labels 1/40 of the height or 1/24 of the width, the smaller, at least 10 px).
/// The title is any bytes (invalid UTF-8 drawn as U+FFFD), shortened with an ellipsis beyond 45%
/// of the width or 512 characters. Throws Error(Argument) for an image below kLegendMinWidth x
/// kLegendMinHeight or a bad range (as legendTicks).
LegendLayout drawLegend(Image& image, const Font& font, const TransferFunction& tf, double lo,
                        double hi, const std::string& title, bool logScale,
                        const LegendStyle& style = {});

/// Where drawLegend would put a legend of these arguments on an image of width x height,
/// without drawing: its columns (LegendLayout::columns) are known before the frame is
/// rendered, so that its camera can keep the volume off them (clearColumns). tickRows stays
/// empty. Throws as drawLegend for a bad range.
LegendLayout legendLayout(int width, int height, const Font& font, double lo, double hi,
                          const std::string& title, bool logScale, const LegendStyle& style = {});

/// The camera of a frame of `mesh` that will carry a legend at the right edge (issue 35):
/// settings.camera (none: the reset camera of fileBounds, the rendered cells' bounds in the
/// file's coordinates) moved by clearColumns (back where needed, and sideways) so that the
/// volume stays off the columns of the legend drawn with the frame's range (frameValueRange)
/// and `title`. For a camera that is the reset one, perhaps turned or zoomed: the CLI's render
/// and animate and Python's render(legend=True) use it, not for a camera placed by the user.
Camera cameraBesideLegend(const PreparedMesh& mesh, const RenderSettings& settings,
                          const Bounds3f& fileBounds, const Font& font, const std::string& title);

/// Draws one line of text at the image's top-left corner on a box as drawLegend's (the
/// background's colour, 80%; ink contrasting), sized as the legend's labels: ParaView's
/// Annotate Time ("Time: 0.5") on an animation's frames. Returns the box. Throws as drawLegend
/// for an image below kLegendMinWidth x kLegendMinHeight.
PixelRect drawCornerText(Image& image, const Font& font, const std::string& text,
                         const LegendStyle& style = {});

}  // namespace uvr
