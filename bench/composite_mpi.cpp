// SPDX-License-Identifier: MIT
// Compositing alone under mpirun (issue 31; docs/PERFORMANCE.md): every rank holds a frame of
// premultiplied colours and sample counts over the part of the image its piece covers, and
// compositeFrame blends them onto rank 0 (direct send, the second pass on). The ranks meet at a
// barrier before each call, so the time is the exchange and the blending, not a wait for a
// slower rank's frame. Rank 0 prints the median and fastest call as JSON.
//
//   mpirun -n 4 bench/uvr_composite_mpi --size 1024x1024 --repeat 30 [--cover 0.5]
//                                      [--fresh-buffers]
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/dist/composite.h"
#include "uvr/dist/mpi_communicator.h"

int main(int argc, char** argv) {
    using namespace uvr;
    CLI::App app("Times compositeFrame under mpirun with synthetic frames");
    std::string size = "1024x1024";
    int repeat = 30;
    double cover = 0.5;
    app.add_option("--size", size, "Frame size WxH")->capture_default_str();
    app.add_option("--repeat", repeat, "Timed calls")
        ->check(CLI::Range(1, 100000))
        ->capture_default_str();
    app.add_option("--cover", cover,
                   "Fraction of the image's columns each rank's piece covers (1: all of it)")
        ->check(CLI::Range(0.01, 1.0))
        ->capture_default_str();
    bool fresh = false;
    app.add_flag("--fresh-buffers", fresh,
                 "Each call with buffers of its own (pages mapped anew), not the ones kept from "
                 "the call before as a renderer keeps them");
    CLI11_PARSE(app, argc, argv);
    int width = 0, height = 0;
    if (std::sscanf(size.c_str(), "%dx%d", &width, &height) != 2 || width < 1 || height < 1) {
        std::fprintf(stderr, "uvr_composite_mpi: --size %s: expected WxH\n", size.c_str());
        return 2;
    }
    try {
        Communicator& comm = mpiWorld();
        const int ranks = comm.size(), me = comm.rank();
        // Rank r's piece covers a run of columns, the runs of neighbouring ranks overlapping.
        const int span = std::max(1, static_cast<int>(cover * width));
        const int x0 = ranks > 1 ? (width - span) * me / (ranks - 1) : 0;
        std::mt19937 rng(7 + me);
        std::uniform_real_distribution<float> u(0.f, 1.f);
        Image frame(width, height);
        std::vector<std::uint32_t> counts(std::size_t(width) * height, 0);
        for (int y = 0; y < height; ++y)
            for (int x = x0; x < x0 + span; ++x) {
                const float a = 0.6f * u(rng);
                const std::size_t i = std::size_t(y) * width + x;
                frame.pixels[i] = Vec4f(a * u(rng), a * u(rng), a * u(rng), a);
                counts[i] = 1 + static_cast<std::uint32_t>(20 * u(rng));
            }
        std::vector<int> order(ranks);
        for (int r = 0; r < ranks; ++r) order[r] = r;
        CompositeBuffers buffers;  // kept from call to call, as a renderer keeps them
        CompositeOptions options;
        options.stopAlpha = 0.99f;
        options.restop = true;
        options.rerender = [&](const PieceAsks& asks, PieceFrame& again) {
            // An empty second pass: the asks and answers only.
            again.image = Image(width, height);
            again.counts.assign(asks.stops.size(), 0);
        };
        options.buffers = fresh ? nullptr : &buffers;
        std::vector<float> depth;  // no depth out
        std::vector<double> seconds;
        std::uint64_t bytes = 0;
        for (int k = 0; k < repeat + 2; ++k) {
            Image image = frame;
            std::vector<std::uint32_t> c = counts;
            comm.barrier();
            const auto start = std::chrono::steady_clock::now();
            const CompositeStats stats = compositeFrame(comm, image, c, depth, order, options);
            const double s =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            if (k >= 2) seconds.push_back(s);  // two warm-up calls
            bytes = stats.bytesSent;
        }
        std::sort(seconds.begin(), seconds.end());
        const double median = seconds[seconds.size() / 2];
        std::vector<double> medians = comm.allGatherValues(median);
        if (me == 0)
            std::printf(
                "{\"ranks\": %d, \"width\": %d, \"height\": %d, \"cover\": %g, "
                "\"median_ms\": %.3f, \"slowest_rank_median_ms\": %.3f, "
                "\"fastest_ms\": %.3f, \"rank0_bytes_sent\": %llu, \"fresh_buffers\": %s}\n",
                ranks, width, height, cover, median * 1e3,
                *std::max_element(medians.begin(), medians.end()) * 1e3, seconds.front() * 1e3,
                static_cast<unsigned long long>(bytes), fresh ? "true" : "false");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "uvr_composite_mpi: %s\n", e.what());
        return 1;
    }
    return 0;
}
