// SPDX-License-Identifier: MIT
#pragma once

// Why a rendered frame came out empty (issue 15: no silent empties). A user who gets a
// transparent image with exit 0 needs the reason: the field is constant, --range misses the
// data, the mesh is not in view, or the transfer function is transparent over the field's values.

#include <string>

#include "uvr/render/frame_setup.h"

namespace uvr {

/// Opacity below which a pixel counts as empty: half an 8-bit level.
inline constexpr float kEmptyPixelAlpha = 0.5f / 255.f;

/// "" when some pixel of the frame reaches kEmptyPixelAlpha; else one sentence saying why the
/// frame is empty: no pixel's ray meets the mesh's bounds; or the transfer function is
/// transparent over the field's values, because the field is constant, because --range misses
/// them, or as it is; else opacity too low for the mesh's size.
std::string explainEmptyFrame(const PreparedMesh& mesh, const RenderSettings& settings,
                              const RenderResult& result);

}  // namespace uvr
