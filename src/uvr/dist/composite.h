// SPDX-License-Identifier: MIT
#pragma once

// Sort-last compositing of a data-parallel frame (issue 31): every rank's premultiplied image of
// its box, composited per pixel front to back in the boxes' visibility order.

#include <cstdint>
#include <functional>
#include <vector>

#include "uvr/dist/communicator.h"
#include "uvr/render/image.h"

namespace uvr {

/// What compositing one frame cost this rank.
struct CompositeStats {
    double seconds = 0.0;         ///< wall time of the exchange and the blending (no rendering)
    std::uint64_t bytesSent = 0;  ///< bytes this rank sent
    std::uint64_t rerenderedPixels = 0;  ///< pixels this rank rendered again (the second pass)
    double rerenderSeconds = 0.0;        ///< its second pass's rendering
};

/// The second pass of compositeFrame: renders this rank's piece again with a stop opacity per
/// pixel (`stops`, width x height, RenderSettings::pixelStopAlpha: 0 for a pixel not asked
/// for), into `image` and `counts` (samples per pixel).
using RerenderPiece = std::function<void(const std::vector<float>& stops, Image& image,
                                         std::vector<std::uint32_t>& counts)>;

/// What compositeFrame keeps from one frame to the next: the messages sent and received, the
/// band being blended and the bands root gathers.
struct CompositeBuffers {
    std::vector<std::vector<std::byte>> toEach, parts, bands;
    std::vector<Vec4f> band;
    std::vector<std::uint32_t> bandCounts;
    std::vector<std::byte> mine;
};

/// The rows [first, end) of an image of `height` rows that rank `rank` of `ranks` composites
/// (direct send: one band of rows each, as even as the rows allow).
std::pair<int, int> compositeBand(int height, int rank, int ranks);

/// Composites one frame over the ranks (collective): each pixel is every rank's premultiplied
/// RGBA blended front to back in `order` (visibilityOrder: every rank's, each once), in float,
/// and the per-pixel sample counts are summed. A pixel takes no more ranks once its opacity
/// reaches stopAlpha (the integrators' early termination: one process's ray stops there too).
///
/// With `rerender` (the sampling methods, whose stop is below 1), the picture is one process's:
/// where a rank's ray reached its own stopAlpha behind ranks that already held opacity a, one
/// process's ray stopped earlier, where the whole opacity reached stopAlpha; such a pixel is
/// rendered again by that rank, stopping at (stopAlpha - a) / (1 - a), and replaces its first
/// colour (one more exchange, only when some pixel asks for it).
///
/// Direct send: rank r blends band r of every rank's image (compositeBand), then `root` gathers the
/// bands. A rank sends only the part of each band inside the box of its pixels that hold any
/// opacity or samples (outside it, blending its image changes nothing). On root, `image` and
/// `counts` become the whole frame's; elsewhere they are left as they were. Every rank's image
/// must have the same size, and counts width * height entries (or none on every rank).
///
/// `buffers` (a renderer's, kept from frame to frame; null: the call's own) hold the messages
/// and the band, so their pages stay mapped: fresh ones cost more than the exchange itself.
CompositeStats compositeFrame(Communicator& comm, Image& image, std::vector<std::uint32_t>& counts,
                              const std::vector<int>& order, int root = 0, float stopAlpha = 1.f,
                              const RerenderPiece& rerender = {},
                              CompositeBuffers* buffers = nullptr);

}  // namespace uvr
