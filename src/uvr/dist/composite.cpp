// SPDX-License-Identifier: MIT
#include "uvr/dist/composite.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <span>

#include "uvr/core/error.h"

namespace uvr {

std::pair<int, int> compositeBand(int height, int rank, int ranks) {
    const auto at = [&](int r) {
        return static_cast<int>(std::int64_t(height) * r / std::max(ranks, 1));
    };
    return {at(rank), at(rank + 1)};
}

namespace {

/// The pixels [x0, x1) x [y0, y1) of an image that hold anything: some opacity or some samples
/// (empty, x0 = x1, when none does). Outside it a rank's image is transparent and sampled
/// nowhere, so blending it there changes nothing.
struct PixelBox {
    std::int32_t x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

PixelBox activeBox(const Image& image, const std::vector<std::uint32_t>& counts) {
    const int w = image.width, h = image.height;
    const auto holds = [&](int x, int y) {
        const std::size_t i = std::size_t(y) * w + x;
        return image.pixels[i].w != 0.f || (!counts.empty() && counts[i] != 0);
    };
    const auto rowHolds = [&](int y) {
        for (int x = 0; x < w; ++x)
            if (holds(x, y)) return true;
        return false;
    };
    // The first and last rows holding anything, then in the rows between each row's first and
    // last pixel, scanning only as far as the box so far: a frame the piece fills costs a few
    // pixels a row, not every pixel.
    int y0 = 0, y1 = h;
    while (y0 < h && !rowHolds(y0)) ++y0;
    if (y0 == h) return {};
    while (!rowHolds(y1 - 1)) --y1;
    int x0 = w, x1 = 0;
    for (int y = y0; y < y1; ++y) {
        for (int x = 0; x < x0; ++x)
            if (holds(x, y)) {
                x0 = x;
                break;
            }
        for (int x = w - 1; x >= x1; --x)
            if (holds(x, y)) {
                x1 = x + 1;
                break;
            }
    }
    return {x0, y0, x1, y1};
}

/// A pixel the second pass renders again: the opacity its ray stops at, and the one whose
/// depth it notes (0: none).
struct StopAsk {
    std::uint32_t pixel;  ///< index in the whole image
    float stop;
    float depthAlpha;
};

/// What a band owner keeps of an ask: the band's pixel, the colour in front of the rank asked,
/// and what the answer replaces (the colour behind that front: a stop asked; the depth: a
/// depth asked).
struct AskFront {
    std::size_t i;
    Vec4f front;
    bool restop, depth;
};

/// compositeFrame's second pass (collective): each rank renders again the pixels the band
/// owners ask of it (asks[r]: this band's asks of rank r; fronts[r]: what the band keeps of
/// them), and the band takes the new colours behind those fronts and the depths asked for.
void secondCompositingPass(Communicator& comm, const Image& image, bool depthOn,
                           const std::vector<std::vector<StopAsk>>& asks,
                           const std::vector<std::vector<AskFront>>& fronts, CompositeBuffers& b,
                           const RerenderPiece& rerender, CompositeStats& stats) {
    const int ranks = comm.size(), me = comm.rank();
    std::uint64_t total = 0;
    for (const std::vector<StopAsk>& a : asks) total += a.size();
    comm.allReduce(std::span<std::uint64_t>(&total, 1), ReduceOp::Sum);
    if (total == 0) return;  // nothing to redo
    std::vector<std::vector<std::byte>> out(ranks);
    for (int r = 0; r < ranks; ++r) {
        appendBytes(out[r], asks[r].data(), asks[r].size());
        if (r != me) stats.bytesSent += out[r].size();
    }
    std::vector<std::vector<StopAsk>> asked(ranks);
    {
        const std::vector<std::vector<std::byte>> in = comm.allToAll(out);
        for (int r = 0; r < ranks; ++r) asked[r] = fromBytes<StopAsk>(in[r]);
    }
    for (const std::vector<StopAsk>& a : asked) stats.rerenderedPixels += a.size();
    PieceFrame again;
    std::exception_ptr failure;
    if (stats.rerenderedPixels > 0) {
        const auto start = std::chrono::steady_clock::now();
        try {
            PieceAsks piece;
            piece.stops.assign(image.pixels.size(), 0.f);
            if (depthOn) piece.depthAlphas.assign(image.pixels.size(), 0.f);
            for (int r = 0; r < ranks; ++r)
                for (const StopAsk& a : asked[r]) {
                    UVR_CHECK(a.pixel < piece.stops.size() && a.stop > 0.f && a.stop <= 1.f &&
                                  a.depthAlpha >= 0.f && a.depthAlpha <= 1.f &&
                                  (depthOn || a.depthAlpha == 0.f),
                              "rank " << r << " asked for pixel " << a.pixel << " to stop at "
                                      << a.stop << " with depth at " << a.depthAlpha);
                    piece.stops[a.pixel] = a.stop;
                    if (depthOn) piece.depthAlphas[a.pixel] = a.depthAlpha;
                }
            rerender(piece, again);
            UVR_CHECK(again.image.pixels.size() == piece.stops.size() &&
                          (again.counts.empty() || again.counts.size() == piece.stops.size()) &&
                          (!depthOn || again.depth.size() == piece.stops.size()),
                      "the second pass's frame has the first one's size");
        } catch (...) {
            failure = std::current_exception();
        }
        stats.rerenderSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    comm.agree(failure);
    // The answers, in each asker's order: colour, samples and, with depth out, depth.
    for (int r = 0; r < ranks; ++r) {
        out[r].clear();
        for (const StopAsk& a : asked[r]) {
            const std::uint32_t c = again.counts.empty() ? 0u : again.counts[a.pixel];
            appendBytes(out[r], &again.image.pixels[a.pixel], 1);
            appendBytes(out[r], &c, 1);
            if (depthOn) appendBytes(out[r], &again.depth[a.pixel], 1);
        }
        if (r != me) stats.bytesSent += out[r].size();
    }
    const std::vector<std::vector<std::byte>> answers = comm.allToAll(out);
    const std::size_t answer =
        sizeof(Vec4f) + sizeof(std::uint32_t) + (depthOn ? sizeof(float) : 0);
    for (int r = 0; r < ranks; ++r) {
        UVR_CHECK(answers[r].size() == fronts[r].size() * answer,
                  "rank " << r << " answered " << answers[r].size() << " bytes for "
                          << fronts[r].size() << " pixels");
        for (std::size_t k = 0; k < fronts[r].size(); ++k) {
            const AskFront& f = fronts[r][k];
            const std::byte* at = answers[r].data() + k * answer;
            Vec4f px;
            std::uint32_t c = 0;
            std::memcpy(&px, at, sizeof(Vec4f));
            std::memcpy(&c, at + sizeof(Vec4f), sizeof(c));
            if (f.restop) {  // no rank was blended behind it: its opacity reached the stop
                const float t = 1.f - f.front.w;
                b.band[f.i] = Vec4f(f.front.x + t * px.x, f.front.y + t * px.y,
                                    f.front.z + t * px.z, f.front.w + t * px.w);
            }
            if (f.depth)
                std::memcpy(&b.bandDepth[f.i], at + sizeof(Vec4f) + sizeof(c), sizeof(float));
            if (!b.bandCounts.empty()) b.bandCounts[f.i] += c;
        }
    }
}

}  // namespace

CompositeStats compositeFrame(Communicator& comm, Image& image, std::vector<std::uint32_t>& counts,
                              std::vector<float>& depth, const std::vector<int>& order,
                              const CompositeOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    CompositeBuffers own;
    CompositeBuffers& b = options.buffers ? *options.buffers : own;
    CompositeStats stats;
    const int ranks = comm.size(), me = comm.rank();
    UVR_CHECK(int(order.size()) == ranks,
              "visibility order of " << order.size() << " ranks, not " << ranks);
    const std::size_t width = static_cast<std::size_t>(image.width);
    const bool withCounts = !counts.empty();
    UVR_CHECK(!withCounts || counts.size() == image.pixels.size(), "sample counts' size");
    const float depthAlpha = options.depthAlpha;
    const bool depthOn = depthAlpha > 0.f;
    UVR_CHECK(depthOn ? depth.size() == image.pixels.size() : depth.empty(),
              "depths' size: " << depth.size() << " for " << image.pixels.size() << " pixels");
    UVR_CHECK(depthAlpha <= 1.f, "depth out at opacity " << depthAlpha);
    const bool secondPass = options.restop || depthOn;
    UVR_CHECK(!secondPass || options.rerender, "a second pass without a renderer");
    const float stopAlpha = options.stopAlpha;
    // What each pixel of the messages and the bands holds: a colour, then a count and a depth.
    const std::size_t pixelBytes =
        sizeof(Vec4f) + (withCounts ? sizeof(std::uint32_t) : 0) + (depthOn ? sizeof(float) : 0);
    // Every rank's share of band r goes to rank r: the part of band r inside the box of its
    // pixels that hold anything (a header, then the box's rows of colours, of counts, of depths).
    const PixelBox active = activeBox(image, counts);
    std::vector<std::vector<std::byte>>& toEach = b.toEach;
    toEach.resize(ranks);
    const auto partOfBand = [&](int r) {
        const auto [first, end] = compositeBand(image.height, r, ranks);
        PixelBox part = active;
        part.y0 = std::max(part.y0, first), part.y1 = std::min(part.y1, end);
        if (part.y1 <= part.y0 || part.x1 <= part.x0) part = {};
        return part;
    };
    for (int r = 0; r < ranks; ++r) {
        toEach[r].clear();
        if (r == me) continue;  // blended straight from the image
        const PixelBox part = partOfBand(r);
        appendBytes(toEach[r], &part, 1);
        const std::size_t w = part.x1 - part.x0;
        for (int y = part.y0; y < part.y1; ++y)
            appendBytes(toEach[r], image.pixels.data() + y * width + part.x0, w);
        if (withCounts)
            for (int y = part.y0; y < part.y1; ++y)
                appendBytes(toEach[r], counts.data() + y * width + part.x0, w);
        if (depthOn)
            for (int y = part.y0; y < part.y1; ++y)
                appendBytes(toEach[r], depth.data() + y * width + part.x0, w);
        stats.bytesSent += toEach[r].size();
    }
    comm.allToAllInto(toEach, b.parts);
    const std::vector<std::vector<std::byte>>& parts = b.parts;
    // Band `me`: front to back over the ranks (premultiplied "over"), blended straight from the
    // bytes received.
    const auto [first, end] = compositeBand(image.height, me, ranks);
    const std::size_t n = (end - first) * width;
    std::vector<Vec4f>& band = b.band;
    band.assign(n, Vec4f(0.f, 0.f, 0.f, 0.f));
    std::vector<std::uint32_t>& bandCounts = b.bandCounts;
    bandCounts.assign(withCounts ? n : 0, 0);
    std::vector<float>& bandDepth = b.bandDepth;
    bandDepth.assign(depthOn ? n : 0, INFINITY);
    // The second pass's asks: per rank, the pixels it renders again, and what the band keeps of
    // each.
    std::vector<std::vector<StopAsk>> asks(ranks);
    std::vector<std::vector<AskFront>> fronts(ranks);
    for (int r : order) {
        // Rank r's part of the band: its box, and its rows of colours, counts and depths, each
        // row `stride` pixels after the one before (the bytes received, or this rank's image).
        PixelBox box;
        const std::byte *colours, *samples, *depths;
        std::size_t stride;
        if (r == me) {
            box = partOfBand(me);
            const std::size_t at = std::size_t(box.y0) * width + box.x0;
            colours = reinterpret_cast<const std::byte*>(image.pixels.data() + at);
            samples = withCounts ? reinterpret_cast<const std::byte*>(counts.data() + at) : nullptr;
            depths = depthOn ? reinterpret_cast<const std::byte*>(depth.data() + at) : nullptr;
            stride = width;
        } else {
            const std::vector<std::byte>& part = parts[r];
            UVR_CHECK(part.size() >= sizeof box, "rank " << r << " sent no box");
            std::memcpy(&box, part.data(), sizeof box);
            const bool none = box.x0 == box.x1 || box.y0 == box.y1;
            UVR_CHECK(none || (box.x0 >= 0 && box.x0 < box.x1 && box.x1 <= image.width &&
                               box.y0 >= first && box.y0 < box.y1 && box.y1 <= end),
                      "rank " << r << " sent a box outside band [" << first << ", " << end << ")");
            const std::size_t pixels = none ? 0 : std::size_t(box.x1 - box.x0) * (box.y1 - box.y0);
            UVR_CHECK(part.size() == sizeof box + pixels * pixelBytes,
                      "rank " << r << " sent " << part.size() << " bytes for a box of " << pixels
                              << " pixels");
            colours = part.data() + sizeof box;
            samples = colours + pixels * sizeof(Vec4f);
            depths = samples + (withCounts ? pixels * sizeof(std::uint32_t) : 0);
            stride = box.x1 - box.x0;
        }
        const bool empty = box.x0 == box.x1 || box.y0 == box.y1;
        const std::size_t w = empty ? 0 : box.x1 - box.x0;
        // One thread: the blend is bound by memory, and OpenMP's waiting threads cost ranks
        // that share cores more than threads gain (4 ranks on 2 cores: 3-4x slower).
        const int rows = empty ? 0 : box.y1 - box.y0;
        for (int row = 0; row < rows; ++row) {
            // k: the source's pixel, i: the same pixel in the band.
            std::size_t k = std::size_t(row) * stride;
            std::size_t i = (std::size_t(box.y0 + row) - first) * width + box.x0;
            for (std::size_t x = 0; x < w; ++x, ++k, ++i) {
                if (withCounts) {
                    std::uint32_t c;
                    std::memcpy(&c, samples + k * sizeof c, sizeof c);
                    bandCounts[i] += c;
                }
                Vec4f& acc = band[i];
                if (acc.w >= stopAlpha) continue;
                Vec4f px;
                std::memcpy(&px, colours + k * sizeof px, sizeof px);
                const Vec4f front = acc;
                const float t = 1.f - acc.w;
                acc.x += t * px.x, acc.y += t * px.y, acc.z += t * px.z;
                acc.w += t * px.w;
                // Rank r's ray stopped at its own stopAlpha; one process's stopped where the
                // whole opacity reached it, which the light in front moves forward.
                const bool restop = options.restop && front.w > 0.f && acc.w >= stopAlpha;
                // The whole opacity reaches depthAlpha in rank r's light: where its own
                // does, with no light in front; else where its own reaches what the front
                // leaves.
                float depthAsk = 0.f;
                if (depthOn && front.w < depthAlpha && acc.w >= depthAlpha) {
                    if (front.w > 0.f)
                        depthAsk = (depthAlpha - front.w) / (1.f - front.w);
                    else
                        std::memcpy(&bandDepth[i], depths + k * sizeof(float), sizeof(float));
                }
                if (restop || depthAsk > 0.f) {
                    asks[r].push_back({static_cast<std::uint32_t>(first * width + i),
                                       restop ? (stopAlpha - front.w) / (1.f - front.w) : stopAlpha,
                                       depthAsk});
                    fronts[r].push_back({i, front, restop, depthAsk > 0.f});
                }
            }
        }
    }
    if (secondPass)
        secondCompositingPass(comm, image, depthOn, asks, fronts, b, options.rerender, stats);
    // The bands to root.
    const int root = options.root;
    std::vector<std::byte>& mine = b.mine;
    mine.clear();
    if (me != root) {  // root's own band goes straight into its image
        appendBytes(mine, band.data(), n);
        if (withCounts) appendBytes(mine, bandCounts.data(), n);
        if (depthOn) appendBytes(mine, bandDepth.data(), n);
        stats.bytesSent += mine.size();
    }
    comm.gatherInto(mine, root, b.bands);
    const std::vector<std::vector<std::byte>>& bands = b.bands;
    if (me == root) {
        std::copy(band.begin(), band.end(), image.pixels.begin() + first * width);
        if (withCounts)
            std::copy(bandCounts.begin(), bandCounts.end(), counts.begin() + first * width);
        if (depthOn) std::copy(bandDepth.begin(), bandDepth.end(), depth.begin() + first * width);
        for (int r = 0; r < ranks; ++r) {
            if (r == root) continue;
            const auto [f, e] = compositeBand(image.height, r, ranks);
            const std::size_t m = (e - f) * width;
            UVR_CHECK(bands[r].size() == m * pixelBytes, "rank " << r << "'s band");
            const std::byte* at = bands[r].data();
            std::memcpy(image.pixels.data() + f * width, at, m * sizeof(Vec4f));
            at += m * sizeof(Vec4f);
            if (withCounts) {
                std::memcpy(counts.data() + f * width, at, m * sizeof(std::uint32_t));
                at += m * sizeof(std::uint32_t);
            }
            if (depthOn) std::memcpy(depth.data() + f * width, at, m * sizeof(float));
        }
    }
    stats.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() -
        stats.rerenderSeconds;
    return stats;
}

}  // namespace uvr
