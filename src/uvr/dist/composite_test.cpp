// SPDX-License-Identifier: MIT
// Sort-last compositing on its own (the renderer's data-parallel tests compare whole frames with
// one process's): each rank sends only the box of its pixels that hold anything, and the frame
// is the front-to-back blend of every rank's whole image.
#include "uvr/dist/composite.h"

#include <gtest/gtest.h>

#include <mutex>
#include <random>
#include <vector>

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
        const CompositeStats s = compositeFrame(comm, image, c, order, 0);
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

}  // namespace
}  // namespace uvr
