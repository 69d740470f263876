// SPDX-License-Identifier: MIT
#include "uvr/server/view_frame.h"

#include <gtest/gtest.h>
#include <turbojpeg.h>

#include "test_meshes.h"
#include "uvr/tf/transfer_function.h"

namespace uvr::server {
namespace {

/// Width, height and PNG colour type (2: RGB, 6: RGBA) from a PNG's IHDR chunk.
struct PngHeader {
    int width = 0, height = 0, colorType = -1;
};
PngHeader pngHeader(const std::vector<std::uint8_t>& png) {
    static const std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    PngHeader h;
    if (png.size() < 26 || !std::equal(kSignature, kSignature + 8, png.begin())) return h;
    auto be32 = [&](std::size_t at) {
        return int(png[at]) << 24 | int(png[at + 1]) << 16 | int(png[at + 2]) << 8 | png[at + 3];
    };
    h.width = be32(16), h.height = be32(20), h.colorType = png[25];
    return h;
}

class ViewFrameTest : public ::testing::Test {
protected:
    ViewFrameTest()
        : mesh_(testing::makeHexGrid(
              5, -1.f, 1.f, [](Vec3f p) { return p.x + p.y; }, 0.f)),
          renderer_(mesh_, selectScalarField(mesh_, {}), options()) {
        state_.camera = resetCamera(mesh_.bounds(), 64.f / 48.f);
        state_.tf = transferFunctionPreset("viridis");
        applyOpacitySpec(state_.tf, "0:0,1:0.6");
        state_.range = {-2.f, 2.f};
        state_.width = 64, state_.height = 48;
    }
    static RendererOptions options() {
        RendererOptions o;
        o.device = Device::Cpu;
        return o;
    }
    Mesh mesh_;
    Renderer renderer_;
    ViewState state_;
};

TEST_F(ViewFrameTest, AReducedFrameIsAJpegOfFewerPixelsWithTheFrameReport) {
    const ViewFrame f =
        renderViewFrame(renderer_, state_, RenderSettings{}, FrameKind::Reduced, 4, 7, {});
    EXPECT_EQ(f.meta["type"], "frame");
    EXPECT_EQ(f.meta["format"], "jpeg");
    EXPECT_EQ(f.meta["full"], false);
    EXPECT_EQ(f.meta["scale"], 4);
    EXPECT_EQ(f.meta["seq"], 7);
    EXPECT_EQ(f.meta["width"], 16);
    EXPECT_EQ(f.meta["height"], 12);
    // The library's report, and what only the server adds.
    EXPECT_TRUE(f.meta["stats"].contains("method"));
    EXPECT_EQ(f.meta["stats"]["bytes"], f.bytes.size());
    EXPECT_GE(f.meta["stats"]["frame_seconds"].get<double>(), 0.0);
    EXPECT_GT(f.msPerPixel, 0.0);
    tjhandle d = tjInitDecompress();
    int w = 0, h = 0, sub = 0, space = 0;
    ASSERT_EQ(tjDecompressHeader3(d, f.bytes.data(), f.bytes.size(), &w, &h, &sub, &space), 0);
    tjDestroy(d);
    EXPECT_EQ(w, 16);
    EXPECT_EQ(h, 12);
}

TEST_F(ViewFrameTest, AFullFrameIsAnOpaquePngAndASnapshotKeepsItsAlpha) {
    const ViewFrame full =
        renderViewFrame(renderer_, state_, RenderSettings{}, FrameKind::Full, 1, 3, {});
    EXPECT_EQ(full.meta["format"], "png");
    EXPECT_EQ(full.meta["full"], true);
    const PngHeader fh = pngHeader(full.bytes);
    EXPECT_EQ(fh.width, 64);
    EXPECT_EQ(fh.height, 48);
    EXPECT_EQ(fh.colorType, 2);  // composited over the background: RGB
    // A snapshot: full size whatever the scale asked, transparent where the volume is, no
    // statistics.
    const ViewFrame snap =
        renderViewFrame(renderer_, state_, RenderSettings{}, FrameKind::Snapshot, 4, 3, {});
    EXPECT_EQ(snap.meta["type"], "snapshot");
    EXPECT_FALSE(snap.meta.contains("stats"));
    const PngHeader sh = pngHeader(snap.bytes);
    EXPECT_EQ(sh.width, 64);
    EXPECT_EQ(sh.height, 48);
    // Over the state's background, as the frames the page showed (issue 35: the saved PNG was
    // transparent while the page showed black).
    EXPECT_EQ(sh.colorType, 2);  // RGB
    ViewState white = state_;
    white.background = Vec3f(1.f, 1.f, 1.f);
    const ViewFrame over =
        renderViewFrame(renderer_, white, RenderSettings{}, FrameKind::Snapshot, 1, 3, {});
    EXPECT_EQ(pngHeader(over.bytes).colorType, 2);
    EXPECT_NE(over.bytes, snap.bytes);  // the corners are white now
}

TEST_F(ViewFrameTest, AHeatMapStateShowsSamplesButNotInSnapshots) {
    const ViewFrame volume =
        renderViewFrame(renderer_, state_, RenderSettings{}, FrameKind::Full, 1, 1, {});
    state_.heatmap = true;
    const ViewFrame heat =
        renderViewFrame(renderer_, state_, RenderSettings{}, FrameKind::Full, 1, 1, {});
    EXPECT_NE(heat.bytes, volume.bytes);
    const ViewFrame snap =
        renderViewFrame(renderer_, state_, RenderSettings{}, FrameKind::Snapshot, 1, 1, {});
    state_.heatmap = false;
    const ViewFrame plain =
        renderViewFrame(renderer_, state_, RenderSettings{}, FrameKind::Snapshot, 1, 1, {});
    EXPECT_EQ(snap.bytes, plain.bytes);
}

}  // namespace
}  // namespace uvr::server
