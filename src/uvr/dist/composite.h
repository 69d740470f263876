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

/// What the second pass of compositeFrame asks of a rank, per pixel (width x height): the
/// opacity at which its ray stops (RenderSettings::pixelStopAlpha; 0: a pixel not asked for)
/// and, with depth out, the opacity whose depth it notes (RenderSettings::pixelDepthAlpha; 0:
/// none; empty without depth).
struct PieceAsks {
    std::vector<float> stops, depthAlphas;
};

/// The second pass's frame of a rank's piece: colours, samples per pixel and, with depth out,
/// depths (RenderResult's).
struct PieceFrame {
    Image image;
    std::vector<std::uint32_t> counts;
    std::vector<float> depth;
};

/// The second pass of compositeFrame: renders this rank's piece again as `asks` say.
using RerenderPiece = std::function<void(const PieceAsks& asks, PieceFrame& frame)>;

/// What compositeFrame keeps from one frame to the next: the messages sent and received, the
/// band being blended and the bands root gathers.
struct CompositeBuffers {
    std::vector<std::vector<std::byte>> toEach, parts, bands;
    std::vector<Vec4f> band;
    std::vector<std::uint32_t> bandCounts;
    std::vector<float> bandDepth;
    std::vector<std::byte> mine;
};

/// The rows [first, end) of an image of `height` rows that rank `rank` of `ranks` composites
/// (direct send: one band of rows each, as even as the rows allow).
std::pair<int, int> compositeBand(int height, int rank, int ranks);

/// How compositeFrame blends a frame.
struct CompositeOptions {
    int root = 0;  ///< the rank that gets the whole frame
    /// A pixel takes no more ranks once its opacity reaches this (the integrators' early
    /// termination: one process's ray stops there too).
    float stopAlpha = 1.f;
    /// Second pass for the stops (the sampling methods, whose stop is below 1): where a rank's ray
    /// reached its own stopAlpha behind ranks that already held opacity a, one process's ray
    /// stopped earlier, where the whole opacity reached stopAlpha; that rank renders the pixel
    /// again, stopping at (stopAlpha - a) / (1 - a), and its colour replaces the first one.
    bool restop = false;
    /// Depth out (RenderSettings::depthAlpha; 0: none): each rank's `depth` holds where its own
    /// opacity reached this. A pixel's depth is the first rank's, in order, whose light takes the
    /// whole opacity to depthAlpha: that rank's own depth where no light is in front of it, else
    /// the second pass asks it for the depth of (depthAlpha - a) / (1 - a).
    float depthAlpha = 0.f;
    RerenderPiece rerender;  ///< the second pass (needed with restop or depthAlpha)
    /// A renderer's buffers, kept from frame to frame (null: the call's own), so their pages stay
    /// mapped: fresh ones cost more than the exchange itself.
    CompositeBuffers* buffers = nullptr;
};

/// Composites one frame over the ranks (collective): each pixel is every rank's premultiplied
/// RGBA blended front to back in `order` (visibilityOrder: every rank's, each once), in float,
/// and the per-pixel sample counts are summed; with depth out, the depths as
/// CompositeOptions::depthAlpha says. The second pass (one more exchange, only when some pixel
/// asks for it) makes the picture one process's.
///
/// Direct send: rank r blends band r of every rank's image (compositeBand), then options.root
/// gathers the bands. A rank sends only the part of each band inside the box of its pixels that
/// hold any opacity or samples (outside it, blending its image changes nothing). On root,
/// `image`, `counts` and `depth` become the whole frame's; elsewhere they are left as they were.
/// Every rank's image must have the same size; counts width * height entries (or none on every
/// rank); depth width * height with depth out, else none.
CompositeStats compositeFrame(Communicator& comm, Image& image, std::vector<std::uint32_t>& counts,
                              std::vector<float>& depth, const std::vector<int>& order,
                              const CompositeOptions& options = {});

}  // namespace uvr
