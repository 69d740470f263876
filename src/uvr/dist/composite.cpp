// SPDX-License-Identifier: MIT
#include "uvr/dist/composite.h"

#include <chrono>
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

/// Appends n values of a trivially copyable type as bytes.
template <class T>
void appendBytes(std::vector<std::byte>& out, const T* values, std::size_t n) {
    const std::size_t at = out.size();
    out.resize(at + n * sizeof(T));
    if (n) std::memcpy(out.data() + at, values, n * sizeof(T));
}

/// A pixel the second pass renders again, and the opacity its ray stops at.
struct StopAsk {
    std::uint32_t pixel;  ///< index in the whole image
    float stop;
};

/// compositeFrame's second pass (collective): each rank renders again the pixels the band
/// owners ask of it (asks[r]: this band's asks of rank r; fronts[r]: their band index and the
/// colour in front), and the band takes the new colours behind those fronts.
void secondCompositingPass(Communicator& comm, const Image& image,
                           const std::vector<std::vector<StopAsk>>& asks,
                           const std::vector<std::vector<std::pair<std::size_t, Vec4f>>>& fronts,
                           std::vector<Vec4f>& band, std::vector<std::uint32_t>& bandCounts,
                           const RerenderPiece& rerender, CompositeStats& stats) {
    const int ranks = comm.size(), me = comm.rank();
    std::uint64_t total = 0;
    for (const std::vector<StopAsk>& a : asks) total += a.size();
    comm.allReduce(std::span<std::uint64_t>(&total, 1), ReduceOp::Sum);
    if (total == 0) return;  // no ray stopped behind another rank's light: nothing to redo
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
    Image again;
    std::vector<std::uint32_t> againCounts;
    std::exception_ptr failure;
    if (stats.rerenderedPixels > 0) {
        const auto start = std::chrono::steady_clock::now();
        try {
            std::vector<float> stops(image.pixels.size(), 0.f);
            for (int r = 0; r < ranks; ++r)
                for (const StopAsk& a : asked[r]) {
                    UVR_CHECK(
                        a.pixel < stops.size() && a.stop > 0.f && a.stop <= 1.f,
                        "rank " << r << " asked for pixel " << a.pixel << " to stop at " << a.stop);
                    stops[a.pixel] = a.stop;
                }
            rerender(stops, again, againCounts);
            UVR_CHECK(again.pixels.size() == stops.size() &&
                          (againCounts.empty() || againCounts.size() == stops.size()),
                      "the second pass's frame has the first one's size");
        } catch (...) {
            failure = std::current_exception();
        }
        stats.rerenderSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    comm.agree(failure);
    // The answers, in each asker's order: colour and samples.
    for (int r = 0; r < ranks; ++r) {
        out[r].clear();
        for (const StopAsk& a : asked[r]) {
            const std::uint32_t c = againCounts.empty() ? 0u : againCounts[a.pixel];
            appendBytes(out[r], &again.pixels[a.pixel], 1);
            appendBytes(out[r], &c, 1);
        }
        if (r != me) stats.bytesSent += out[r].size();
    }
    const std::vector<std::vector<std::byte>> answers = comm.allToAll(out);
    constexpr std::size_t kAnswer = sizeof(Vec4f) + sizeof(std::uint32_t);
    for (int r = 0; r < ranks; ++r) {
        UVR_CHECK(answers[r].size() == fronts[r].size() * kAnswer,
                  "rank " << r << " answered " << answers[r].size() << " bytes for "
                          << fronts[r].size() << " pixels");
        for (std::size_t k = 0; k < fronts[r].size(); ++k) {
            const auto& [i, front] = fronts[r][k];
            Vec4f px;
            std::uint32_t c = 0;
            std::memcpy(&px, answers[r].data() + k * kAnswer, sizeof(Vec4f));
            std::memcpy(&c, answers[r].data() + k * kAnswer + sizeof(Vec4f), sizeof(c));
            const float t = 1.f - front.w;
            band[i] = Vec4f(front.x + t * px.x, front.y + t * px.y, front.z + t * px.z,
                            front.w + t * px.w);
            if (!bandCounts.empty()) bandCounts[i] += c;
        }
    }
}

}  // namespace

CompositeStats compositeFrame(Communicator& comm, Image& image, std::vector<std::uint32_t>& counts,
                              const std::vector<int>& order, int root, float stopAlpha,
                              const RerenderPiece& rerender) {
    const auto start = std::chrono::steady_clock::now();
    CompositeStats stats;
    const int ranks = comm.size(), me = comm.rank();
    UVR_CHECK(int(order.size()) == ranks,
              "visibility order of " << order.size() << " ranks, not " << ranks);
    const std::size_t width = static_cast<std::size_t>(image.width);
    const bool withCounts = !counts.empty();
    UVR_CHECK(!withCounts || counts.size() == image.pixels.size(), "sample counts' size");
    // Every rank's share of band r goes to rank r.
    std::vector<std::vector<std::byte>> toEach(ranks);
    for (int r = 0; r < ranks; ++r) {
        const auto [first, end] = compositeBand(image.height, r, ranks);
        const std::size_t a = first * width, n = (end - first) * width;
        appendBytes(toEach[r], image.pixels.data() + a, n);
        if (withCounts) appendBytes(toEach[r], counts.data() + a, n);
        if (r != me) stats.bytesSent += toEach[r].size();
    }
    const std::vector<std::vector<std::byte>> parts = comm.allToAll(toEach);
    toEach = {};
    // Band `me`: front to back over the ranks (premultiplied "over").
    const auto [first, end] = compositeBand(image.height, me, ranks);
    const std::size_t n = (end - first) * width;
    const std::size_t pixelBytes = n * sizeof(Vec4f), countBytes = withCounts ? n * 4 : 0;
    std::vector<Vec4f> band(n, Vec4f(0.f, 0.f, 0.f, 0.f));
    std::vector<std::uint32_t> bandCounts(withCounts ? n : 0, 0);
    // The second pass's asks: per rank, the pixels it renders again (band index, the colour in
    // front of it there, the stop sent to it).
    std::vector<std::vector<StopAsk>> asks(ranks);
    std::vector<std::vector<std::pair<std::size_t, Vec4f>>> fronts(ranks);
    const bool secondPass = bool(rerender) && stopAlpha < 1.f;
    for (int r : order) {
        const std::vector<std::byte>& part = parts[r];
        UVR_CHECK(part.size() == pixelBytes + countBytes, "rank " << r << " sent " << part.size()
                                                                  << " bytes for a band of " << n
                                                                  << " pixels");
        const Vec4f* px = reinterpret_cast<const Vec4f*>(part.data());
        for (std::size_t i = 0; i < n; ++i) {
            Vec4f& acc = band[i];
            if (acc.w >= stopAlpha) continue;
            const Vec4f front = acc;
            const float t = 1.f - acc.w;
            acc.x += t * px[i].x, acc.y += t * px[i].y, acc.z += t * px[i].z;
            acc.w += t * px[i].w;
            // Rank r's ray stopped at its own stopAlpha; one process's stopped where the whole
            // opacity reached it, which the light in front moves forward.
            if (secondPass && front.w > 0.f && acc.w >= stopAlpha) {
                asks[r].push_back({static_cast<std::uint32_t>(first * width + i),
                                   (stopAlpha - front.w) / (1.f - front.w)});
                fronts[r].emplace_back(i, front);
            }
        }
        if (withCounts) {
            std::vector<std::uint32_t> c(n);
            std::memcpy(c.data(), part.data() + pixelBytes, countBytes);
            for (std::size_t i = 0; i < n; ++i) bandCounts[i] += c[i];
        }
    }
    if (secondPass)
        secondCompositingPass(comm, image, asks, fronts, band, bandCounts, rerender, stats);
    // The bands to root.
    std::vector<std::byte> mine;
    appendBytes(mine, band.data(), n);
    if (withCounts) appendBytes(mine, bandCounts.data(), n);
    if (me != root) stats.bytesSent += mine.size();
    const std::vector<std::vector<std::byte>> bands = comm.gather(mine, root);
    if (me == root) {
        for (int r = 0; r < ranks; ++r) {
            const auto [f, e] = compositeBand(image.height, r, ranks);
            const std::size_t m = (e - f) * width;
            UVR_CHECK(bands[r].size() == m * (sizeof(Vec4f) + (withCounts ? 4 : 0)),
                      "rank " << r << "'s band");
            std::memcpy(image.pixels.data() + f * width, bands[r].data(), m * sizeof(Vec4f));
            if (withCounts)
                std::memcpy(counts.data() + f * width, bands[r].data() + m * sizeof(Vec4f), m * 4);
        }
    }
    stats.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() -
        stats.rerenderSeconds;
    return stats;
}

}  // namespace uvr
