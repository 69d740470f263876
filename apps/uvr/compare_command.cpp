// SPDX-License-Identifier: MIT
// `uvr compare A.png B.png`: SSIM and PSNR of two images. Exit status: 0 when the images were
// compared (and, with --min-ssim, are similar enough), 1 when SSIM is below --min-ssim, 2 on bad
// input (missing or unreadable file, different sizes, bad flag).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <optional>

#include "cli_common.h"
#include "uvr/render/image_metrics.h"

namespace uvr::cli {

namespace {

/// Exit status for a comparison below the --min-ssim threshold.
constexpr int kBelowThreshold = 1;

std::string sizeText(const Image& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height);
}

}  // namespace

void addCompareCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "compare",
        "Compare two PNG images: SSIM (Wang et al. 2004, as scikit-image computes it) and PSNR. "
        "Exit status 0: compared (and SSIM >= --min-ssim), 1: SSIM below --min-ssim, 2: bad input");
    auto fileA = std::make_shared<std::string>();
    auto fileB = std::make_shared<std::string>();
    auto background = std::make_shared<std::string>("0,0,0");
    auto json = std::make_shared<bool>(false);
    auto minSsim = std::make_shared<std::optional<double>>();
    cmd->add_option("A", *fileA, "First image (.png)")->required();
    cmd->add_option("B", *fileB, "Second image (.png)")->required();
    cmd->add_option("--background", *background,
                    "R,G,B in [0, 1] under transparent pixels before comparing")
        ->capture_default_str();
    cmd->add_flag("--json", *json, "Print JSON instead of text");
    cmd->add_option("--min-ssim", *minSsim,
                    "Exit with status 1 when the mean SSIM is below this value (-1..1)");
    cmd->callback([fileA, fileB, background, json, minSsim, &ctx] {
        const Vec3f bg = parseVec3("--background", *background);
        if (!(bg.x >= 0.f && bg.x <= 1.f && bg.y >= 0.f && bg.y <= 1.f && bg.z >= 0.f &&
              bg.z <= 1.f)) {
            throwError(ErrorKind::Argument, "",
                       "--background " + *background + ": expected three numbers in [0, 1]");
        }
        if (*minSsim && !(**minSsim >= -1.0 && **minSsim <= 1.0)) {
            char text[32];
            std::snprintf(text, sizeof text, "%g", **minSsim);
            throwError(ErrorKind::Argument, "",
                       std::string("--min-ssim ") + text + ": expected a number in -1..1");
        }
        ctx.step("reading " + *fileA + " and " + *fileB);
        const Image a = readPng(*fileA);
        const Image b = readPng(*fileB);
        if (a.width != b.width || a.height != b.height) {
            throwError(ErrorKind::Argument, *fileB,
                       "is " + sizeText(b) + " but " + *fileA + " is " + sizeText(a) +
                           "; expected images of the same size");
        }
        if (a.width < 11 || a.height < 11) {
            throwError(ErrorKind::Argument, *fileA,
                       "is " + sizeText(a) + "; expected at least 11x11 pixels for SSIM");
        }
        const ImageComparison r = compareImages(toRgb8(a, bg), toRgb8(b, bg));
        const bool pass = !*minSsim || r.ssim >= **minSsim;

        if (*json) {
            nlohmann::json j;
            j["a"] = *fileA;
            j["b"] = *fileB;
            j["width"] = a.width;
            j["height"] = a.height;
            j["ssim"] = r.ssim;
            j["ssim_channels"] = {r.ssimChannel[0], r.ssimChannel[1], r.ssimChannel[2]};
            j["psnr"] = std::isinf(r.psnr) ? nlohmann::json(nullptr) : nlohmann::json(r.psnr);
            j["identical"] = r.maxAbsDifference == 0;
            j["max_abs_difference"] = r.maxAbsDifference;
            if (*minSsim) {
                j["min_ssim"] = **minSsim;
                j["pass"] = pass;
            }
            std::printf("%s\n", jsonText(j).c_str());
        } else {
            char psnr[32];
            if (std::isinf(r.psnr))
                std::snprintf(psnr, sizeof psnr, "inf");
            else
                std::snprintf(psnr, sizeof psnr, "%.2f", r.psnr);
            std::printf("SSIM %.6f  PSNR %s dB\n", r.ssim, psnr);
            std::printf("SSIM per channel  R %.6f  G %.6f  B %.6f\n", r.ssimChannel[0],
                        r.ssimChannel[1], r.ssimChannel[2]);
            std::printf("max difference %g of 255\n", r.maxAbsDifference);
            if (*minSsim) {
                std::printf("%s: SSIM %.6f %s --min-ssim %g\n", pass ? "pass" : "FAIL", r.ssim,
                            pass ? ">=" : "<", **minSsim);
            }
        }
        if (!pass) throw CLI::RuntimeError(kBelowThreshold);  // main() returns the code
    });
}

}  // namespace uvr::cli
