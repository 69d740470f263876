// SPDX-License-Identifier: MIT
// `uvr compare A.png B.png`: SSIM, PSNR and the per-pixel measures (99.9th percentile and maximum
// of the difference, pixels off, seams, speckle) of image B against the reference A. Exit status:
// 0 when the images were compared (and meet --min-ssim, --max-p999, --max-diff and --no-seams),
// 1 when they miss one of those, 2 on bad input (missing or unreadable file, different sizes, bad
// flag).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli_common.h"
#include "uvr/render/image_metrics.h"

namespace uvr::cli {

namespace {

/// Exit status for a comparison that misses a threshold (--min-ssim, --max-p999, ...).
constexpr int kBelowThreshold = 1;

std::string sizeText(const Image& image) {
    return std::to_string(image.width) + "x" + std::to_string(image.height);
}

}  // namespace

void addCompareCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "compare",
        "Compare image B with the reference A (two PNG files): SSIM (Wang et al. 2004, as "
        "scikit-image computes it), PSNR, the 99.9th percentile and maximum of the per-pixel "
        "difference, the pixels off by more than 4/255, seams (steps in the difference where A is "
        "smooth, in lines) and speckle (isolated odd pixels). Exit status 0: compared (and every "
        "threshold given met), 1: a threshold missed, 2: bad input");
    auto fileA = std::make_shared<std::string>();
    auto fileB = std::make_shared<std::string>();
    auto background = std::make_shared<std::string>("0,0,0");
    auto json = std::make_shared<bool>(false);
    auto minSsim = std::make_shared<std::optional<double>>();
    auto maxP999 = std::make_shared<std::optional<double>>();
    auto maxDiff = std::make_shared<std::optional<double>>();
    auto noSeams = std::make_shared<bool>(false);
    auto diffImage = std::make_shared<std::string>();
    cmd->add_option("A", *fileA, "Reference image (.png), e.g. the exact integrator's")->required();
    cmd->add_option("B", *fileB, "Image judged against A (.png)")->required();
    cmd->add_option("--background", *background,
                    "R,G,B in [0, 1] under transparent pixels before comparing")
        ->capture_default_str();
    cmd->add_flag("--json", *json, "Print JSON instead of text");
    cmd->add_option("--min-ssim", *minSsim,
                    "Exit with status 1 when the mean SSIM is below this value (-1..1)");
    cmd->add_option("--max-p999", *maxP999,
                    "Exit with status 1 when the 99.9th percentile of the per-pixel difference "
                    "exceeds this many 8-bit levels (0..255)");
    cmd->add_option("--max-diff", *maxDiff,
                    "Exit with status 1 when the largest per-pixel difference exceeds this many "
                    "8-bit levels (0..255)");
    cmd->add_flag("--no-seams", *noSeams, "Exit with status 1 when a seam is found");
    cmd->add_option("--diff-image", *diffImage,
                    "Write the difference image to this PNG: grey 8 x the difference, seam "
                    "pixels red, speckle yellow");
    cmd->callback(
        [fileA, fileB, background, json, minSsim, maxP999, maxDiff, noSeams, diffImage, &ctx] {
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
            for (const auto& [flag, limit] :
                 {std::pair<const char*, const std::optional<double>*>{"--max-p999", maxP999.get()},
                  {"--max-diff", maxDiff.get()}}) {
                if (*limit && !(**limit >= 0.0 && **limit <= 255.0)) {
                    char text[32];
                    std::snprintf(text, sizeof text, "%g", **limit);
                    throwError(ErrorKind::Argument, "",
                               std::string(flag) + " " + text + ": expected a number in 0..255");
                }
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
            const Rgb8Image a8 = toRgb8(a, bg), b8 = toRgb8(b, bg);
            const ImageComparison r = compareImages(a8, b8);
            if (!diffImage->empty()) {
                const Rgb8Image d = differenceImage(a8, b8);
                Image out(d.width, d.height);
                for (size_t i = 0; i < out.pixels.size(); ++i)
                    out.pixels[i] = Vec4f(d.rgb[i * 3] / 255.f, d.rgb[i * 3 + 1] / 255.f,
                                          d.rgb[i * 3 + 2] / 255.f, 1.f);
                writePng(*diffImage, out, Vec3f(0.f, 0.f, 0.f));
            }
            // Each threshold given: its report text and whether it holds.
            struct Check {
                std::string text;
                bool pass;
            };
            std::vector<Check> checks;
            char text[96];
            if (*minSsim) {
                const bool ok = r.ssim >= **minSsim;
                std::snprintf(text, sizeof text, "SSIM %.6f %s --min-ssim %g", r.ssim,
                              ok ? ">=" : "<", **minSsim);
                checks.push_back({text, ok});
            }
            if (*maxP999) {
                const bool ok = r.p999Difference <= **maxP999;
                std::snprintf(text, sizeof text, "99.9th percentile %g %s --max-p999 %g",
                              r.p999Difference, ok ? "<=" : ">", **maxP999);
                checks.push_back({text, ok});
            }
            if (*maxDiff) {
                const bool ok = r.maxAbsDifference <= **maxDiff;
                std::snprintf(text, sizeof text, "max difference %g %s --max-diff %g",
                              r.maxAbsDifference, ok ? "<=" : ">", **maxDiff);
                checks.push_back({text, ok});
            }
            if (*noSeams) {
                std::snprintf(text, sizeof text, "%d seam%s with --no-seams", r.seamCount,
                              r.seamCount == 1 ? "" : "s");
                checks.push_back({text, r.seamCount == 0});
            }
            bool pass = true;
            for (const Check& c : checks) pass = pass && c.pass;

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
                for (const ComparisonField& f : differenceFields(r)) {
                    j[f.name] = f.integer ? nlohmann::json(static_cast<long long>(f.value))
                                          : nlohmann::json(f.value);
                }
                if (*minSsim) j["min_ssim"] = **minSsim;
                if (*maxP999) j["max_p999"] = **maxP999;
                if (*maxDiff) j["max_diff"] = **maxDiff;
                if (*noSeams) j["no_seams"] = true;
                if (!checks.empty()) j["pass"] = pass;
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
                std::printf("%s\n", differenceSummary(r).c_str());
                for (const Check& c : checks)
                    std::printf("%s: %s\n", c.pass ? "pass" : "FAIL", c.text.c_str());
            }
            if (!pass) throw CLI::RuntimeError(kBelowThreshold);  // main() returns the code
        });
}

}  // namespace uvr::cli
