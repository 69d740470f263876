// SPDX-License-Identifier: MIT
// Sort-last compositing on its own (the renderer's data-parallel tests compare whole frames with
// one process's): each rank sends only the box of its pixels that hold anything, and the frame
// is the front-to-back blend of every rank's whole image.
#include "uvr/dist/composite.h"

#include <gtest/gtest.h>

#include <cmath>
#include <mutex>
#include <random>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/dist/in_process_communicator.h"

namespace uvr {
namespace {

constexpr int kWidth = 37, kHeight = 29;

/// Rank r's image: random premultiplied colours inside its box (none for an empty box), 0
/// elsewhere; samples inside the box and in one pixel outside it that holds no colour (a ray
/// that sampled transparent cells).
void rankImage(int r, int x0, int y0, int x1, int y1, Image& image,
               std::vector<std::uint32_t>& counts) {
    image = Image(kWidth, kHeight);
    counts.assign(std::size_t(kWidth) * kHeight, 0u);
    std::mt19937 rng(17 + r);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const float a = u(rng) * 0.7f;
            image.pixels[std::size_t(y) * kWidth + x] =
                Vec4f(a * u(rng), a * u(rng), a * u(rng), a);
            counts[std::size_t(y) * kWidth + x] = 1 + r;
        }
    if (x1 > x0) counts[std::size_t(kHeight - 1) * kWidth + kWidth - 1] = 100;
}

TEST(Composite, OnlyEachRanksBoxIsSentAndTheFrameIsTheWholeBlend) {
    // Boxes: rank 0 the left half, rank 1 a small box across the bands, rank 2 nothing.
    const int boxes[3][4] = {{0, 0, 18, 29}, {20, 5, 30, 12}, {0, 0, 0, 0}};
    const std::vector<int> order = {1, 0, 2};
    // The expected frame: every rank's whole image blended front to back, counts summed.
    std::vector<Image> images(3);
    std::vector<std::vector<std::uint32_t>> counts(3);
    for (int r = 0; r < 3; ++r)
        rankImage(r, boxes[r][0], boxes[r][1], boxes[r][2], boxes[r][3], images[r], counts[r]);
    std::vector<Vec4f> expected(std::size_t(kWidth) * kHeight, Vec4f(0.f, 0.f, 0.f, 0.f));
    std::vector<std::uint32_t> expectedCounts(expected.size(), 0u);
    for (int r : order)
        for (std::size_t i = 0; i < expected.size(); ++i) {
            Vec4f& acc = expected[i];
            expectedCounts[i] += counts[r][i];
            const Vec4f p = images[r].pixels[i];
            const float t = 1.f - acc.w;
            acc.x += t * p.x, acc.y += t * p.y, acc.z += t * p.z;
            acc.w += t * p.w;
        }
    std::mutex mu;
    std::vector<CompositeStats> stats(3);
    Image frame;
    std::vector<std::uint32_t> frameCounts;
    InProcessGroup::run(3, [&](Communicator& comm) {
        const int me = comm.rank();
        Image image = images[me];
        std::vector<std::uint32_t> c = counts[me];
        std::vector<float> depth;  // no depth out
        const CompositeStats s = compositeFrame(comm, image, c, depth, order);
        std::lock_guard lk(mu);
        stats[me] = s;
        if (me == 0) frame = image, frameCounts = c;
    });
    ASSERT_EQ(frame.pixels.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        const Vec4f p = frame.pixels[i], q = expected[i];
        ASSERT_TRUE(p.x == q.x && p.y == q.y && p.z == q.z && p.w == q.w) << "pixel " << i;
    }
    EXPECT_EQ(frameCounts, expectedCounts);
    // Bytes: a box header (16 bytes) to each other rank, the box's pixels (16 bytes of colour,
    // 4 of count) in the other ranks' bands, and the own band to rank 0.
    const auto bandRows = [](int r) {
        const auto [f, e] = compositeBand(kHeight, r, 3);
        return e - f;
    };
    const std::uint64_t bandBytes = std::uint64_t(kWidth) * 20;
    EXPECT_EQ(stats[2].bytesSent, 2u * 16u + bandRows(2) * bandBytes);  // nothing to send
    // Rank 1's box holds 10 x 7 pixels and the lone sampled corner widens it to the image's
    // corner: still less than the whole image it used to send.
    const std::uint64_t whole = std::uint64_t(kWidth) * kHeight * 20;
    EXPECT_LT(stats[1].bytesSent, whole * 2 / 3 + bandRows(1) * bandBytes);
}

/// Depth out, analytically: rank r's piece is, at every pixel, a slab of constant extinction
/// from view depth 10 r' + 1 to 10 r' + 5 (r' its place in the order) of opacity a; its opacity
/// reaches u at 1 + 4 ln(1 - u) / ln(1 - a) into it.
float slabDepth(int place, float a, float u) {
    if (!(u > 0.f) || !(a >= u)) return INFINITY;
    const float f = a < 1.f ? std::log1p(-u) / std::log1p(-a) : 0.f;
    return 10.f * float(place) + 1.f + 4.f * f;
}

TEST(Composite, DepthIsWhereTheWholeOpacityReachesItInTheRankWhoseLightTakesItThere) {
    const std::vector<int> order = {2, 0, 1};
    const float depthAlpha = 0.6f;
    std::vector<int> place(3);
    for (int k = 0; k < 3; ++k) place[order[k]] = k;
    // Opacities: random per rank and pixel, some pixels with one rank alone.
    std::vector<std::vector<float>> alpha(3, std::vector<float>(std::size_t(kWidth) * kHeight));
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    for (std::size_t i = 0; i < alpha[0].size(); ++i)
        for (int r = 0; r < 3; ++r) alpha[r][i] = (i % 7 == 0 && r != 1) ? 0.f : 0.9f * u(rng);
    const auto colourOf = [&](int r, std::size_t i) {
        const float a = alpha[r][i];
        return Vec4f(0.3f * a, 0.5f * a, 0.2f * a, a);
    };
    // One process's depth: the first slab in order where the whole opacity reaches depthAlpha.
    std::vector<float> expected(alpha[0].size(), INFINITY);
    std::size_t behind = 0;  // pixels whose depth lies behind some light
    for (std::size_t i = 0; i < expected.size(); ++i) {
        float front = 0.f;
        for (int r : order) {
            const float after = front + (1.f - front) * alpha[r][i];
            if (front < depthAlpha && after >= depthAlpha) {
                expected[i] =
                    slabDepth(place[r], alpha[r][i], (depthAlpha - front) / (1.f - front));
                behind += front > 0.f;
                break;
            }
            front = after;
        }
    }
    ASSERT_GT(behind, expected.size() / 4);
    std::mutex mu;
    std::vector<float> depth;
    std::uint64_t rerendered = 0;
    Image frame;
    InProcessGroup::run(3, [&](Communicator& comm) {
        const int me = comm.rank();
        Image image(kWidth, kHeight);
        std::vector<std::uint32_t> counts(image.pixels.size(), 1u);
        std::vector<float> mine(image.pixels.size());
        for (std::size_t i = 0; i < mine.size(); ++i) {
            image.pixels[i] = colourOf(me, i);
            mine[i] = slabDepth(place[me], alpha[me][i], depthAlpha);
        }
        CompositeOptions options;
        options.depthAlpha = depthAlpha;
        options.rerender = [&](const PieceAsks& asks, PieceFrame& again) {
            again.image = Image(kWidth, kHeight);
            again.counts.assign(asks.stops.size(), 0u);
            again.depth.assign(asks.stops.size(), INFINITY);
            ASSERT_EQ(asks.depthAlphas.size(), asks.stops.size());
            for (std::size_t i = 0; i < asks.stops.size(); ++i) {
                if (asks.stops[i] == 0.f) continue;
                again.image.pixels[i] = colourOf(me, i);
                again.depth[i] = slabDepth(place[me], alpha[me][i], asks.depthAlphas[i]);
            }
        };
        const CompositeStats s = compositeFrame(comm, image, counts, mine, order, options);
        std::lock_guard lk(mu);
        rerendered += s.rerenderedPixels;
        if (me == 0) depth = mine, frame = image;
    });
    EXPECT_EQ(rerendered, behind);  // the depth in the first slab with light needs no second pass
    ASSERT_EQ(depth.size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i) {
        if (!(expected[i] < INFINITY)) {
            EXPECT_FALSE(depth[i] < INFINITY) << "pixel " << i;
            continue;
        }
        EXPECT_NEAR(depth[i], expected[i], 1e-4f * expected[i]) << "pixel " << i;
        // The colour is the plain blend: the second pass asked for depth only.
        Vec4f acc(0.f, 0.f, 0.f, 0.f);
        for (int r : order) {
            const Vec4f p = colourOf(r, i);
            const float t = 1.f - acc.w;
            acc = Vec4f(acc.x + t * p.x, acc.y + t * p.y, acc.z + t * p.z, acc.w + t * p.w);
        }
        EXPECT_EQ(frame.pixels[i].w, acc.w) << "pixel " << i;
    }
}

TEST(Composite, BadDepthsAreRefused) {
    InProcessGroup::run(2, [&](Communicator& comm) {
        Image image(kWidth, kHeight);
        std::vector<std::uint32_t> counts;
        std::vector<float> depth(3);  // not one per pixel
        CompositeOptions options;
        options.depthAlpha = 0.5f;
        options.rerender = [](const PieceAsks&, PieceFrame&) {};
        EXPECT_THROW(compositeFrame(comm, image, counts, depth, {0, 1}, options), Error);
        options.rerender = {};
        depth.assign(image.pixels.size(), INFINITY);
        EXPECT_THROW(compositeFrame(comm, image, counts, depth, {0, 1}, options), Error);
    });
}

}  // namespace
}  // namespace uvr
