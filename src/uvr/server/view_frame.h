// SPDX-License-Identifier: MIT
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <vector>

#include "uvr/facade/renderer.h"
#include "uvr/server/frame_scheduler.h"
#include "uvr/server/view_state.h"

namespace uvr::server {

/// One frame as the server sends it to a tab: its description (the `frame` or `snapshot`
/// message; docs/VIEWER.md) and the encoded image.
struct ViewFrame {
    nlohmann::json meta;
    std::vector<std::uint8_t> bytes;
    /// What the frame cost per pixel (the render call and the encoding), in milliseconds.
    double msPerPixel = 0.0;
};

/// How frames are encoded (ServerOptions' and the scene's values).
struct FrameEncoding {
    int jpegQuality = 80;  ///< of reduced frames
};

/// Renders `state` over `base` with `renderer` as a frame of `kind` (a reduced one at
/// 1/`scale` of each side) and encodes it: a reduced frame as JPEG, a full one as PNG, both with
/// the library's frame report (frameReport) and the render and encoding times; a snapshot as a
/// PNG at full size, without statistics. A heat map state shows samples per pixel (not in
/// snapshots). `seq` is the state's sequence number the frame answers. Throws what rendering
/// throws.
ViewFrame renderViewFrame(Renderer& renderer, const ViewState& state, const RenderSettings& base,
                          FrameKind kind, int scale, std::uint64_t seq,
                          const FrameEncoding& encoding);

}  // namespace uvr::server
