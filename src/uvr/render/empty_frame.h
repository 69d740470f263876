// SPDX-License-Identifier: MIT
#pragma once

// Why a rendered frame came out empty (issue 15: no silent empties). A user who gets a
// transparent image with exit 0 needs the reason: the field is constant, --range misses the
// data, the mesh is not in view, or the transfer function is transparent over the field's values.

#include <string>

#include "uvr/render/render_setup.h"

namespace uvr {

/// Opacity below which a pixel counts as empty: half an 8-bit level.
inline constexpr float kEmptyPixelAlpha = 0.5f / 255.f;

/// "" when some pixel of the frame reaches kEmptyPixelAlpha; else one sentence saying why the
/// frame is empty, the likeliest cause first: no pixel's ray meets the mesh's bounds; a constant
/// field; a --range that misses the field's values; a transfer function transparent over them;
/// else opacity too low for the mesh's size.
std::string explainEmptyFrame(const PreparedMesh& mesh, const RenderSettings& settings,
                              const RenderResult& result);

}  // namespace uvr
