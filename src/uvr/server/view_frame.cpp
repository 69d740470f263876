// SPDX-License-Identifier: MIT
#include "uvr/server/view_frame.h"

#include <algorithm>
#include <chrono>

#include "uvr/facade/frame_report.h"
#include "uvr/render/heatmap.h"
#include "uvr/render/image.h"
#include "uvr/server/frame_codec.h"

namespace uvr::server {

namespace {

double secondsSince(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

ViewFrame renderViewFrame(Renderer& renderer, const ViewState& state, const RenderSettings& base,
                          FrameKind kind, int scale, std::uint64_t seq,
                          const FrameEncoding& encoding) {
    const bool snapshot = kind == FrameKind::Snapshot;
    const RenderSettings settings = frameSettings(state, base, snapshot ? 1 : scale);
    const auto frameStart = Clock::now();
    const RenderResult result = renderer.render(settings);
    const double frameSeconds = secondsSince(frameStart);
    const auto encodeStart = Clock::now();
    // The heat map's image, else the frame's own (not copied: 16 MB at 1024x1024).
    const bool heatmap = state.heatmap && !snapshot;
    const Image heat =
        heatmap ? sampleHeatmap(result.sampleCounts, settings.width, settings.height, 0) : Image();
    const Image& image = heatmap ? heat : result.image;
    ViewFrame out;
    // Frames and snapshots over the state's background: the saved PNG is what the page showed.
    const Vec3f bg = state.background;
    const char* format = "png";
    if (snapshot)
        out.bytes = encodePng(image, bg);
    else if (kind == FrameKind::Reduced)
        out.bytes = encodeJpeg(image, bg, encoding.jpegQuality), format = "jpeg";
    else
        out.bytes = encodePng(image, bg, 1);
    const double encodeSeconds = secondsSince(encodeStart);
    if (snapshot) {
        out.meta = {{"type", "snapshot"}, {"format", "png"}};
    } else {
        // The library's frame report (the CLI's --stats, Python's stats), and what only the
        // server knows: the whole render call (setup, kernel, read-back), the encoding and the
        // bytes sent.
        nlohmann::json stats = frameReport(renderer, settings, result);
        stats["frame_seconds"] = frameSeconds;
        stats["encode_seconds"] = encodeSeconds;
        stats["bytes"] = out.bytes.size();
        out.meta = {{"type", "frame"},  {"seq", seq},
                    {"format", format}, {"full", kind == FrameKind::Full},
                    {"scale", scale},   {"stats", std::move(stats)}};
        if (!result.setup.notes.empty()) out.meta["notes"] = result.setup.notes;
    }
    out.meta["width"] = image.width;
    out.meta["height"] = image.height;
    const double pixels = double(settings.width) * settings.height;
    out.msPerPixel = (frameSeconds + encodeSeconds) * 1e3 / std::max(1.0, pixels);
    return out;
}

}  // namespace uvr::server
