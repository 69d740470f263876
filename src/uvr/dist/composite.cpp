// SPDX-License-Identifier: MIT
#include "uvr/dist/composite.h"

#include <chrono>
#include <cstring>

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

}  // namespace

CompositeStats compositeFrame(Communicator& comm, Image& image, std::vector<std::uint32_t>& counts,
                              const std::vector<int>& order, int root, float stopAlpha) {
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
    for (int r : order) {
        const std::vector<std::byte>& part = parts[r];
        UVR_CHECK(part.size() == pixelBytes + countBytes, "rank " << r << " sent " << part.size()
                                                                  << " bytes for a band of " << n
                                                                  << " pixels");
        const Vec4f* px = reinterpret_cast<const Vec4f*>(part.data());
        for (std::size_t i = 0; i < n; ++i) {
            Vec4f& acc = band[i];
            if (acc.w >= stopAlpha) continue;
            const float t = 1.f - acc.w;
            acc.x += t * px[i].x, acc.y += t * px[i].y, acc.z += t * px[i].z;
            acc.w += t * px[i].w;
        }
        if (withCounts) {
            std::vector<std::uint32_t> c(n);
            std::memcpy(c.data(), part.data() + pixelBytes, countBytes);
            for (std::size_t i = 0; i < n; ++i) bandCounts[i] += c[i];
        }
    }
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
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return stats;
}

}  // namespace uvr
