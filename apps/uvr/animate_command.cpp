// SPDX-License-Identifier: MIT
// `uvr animate`: every time step of a file or series to numbered PNGs, the mesh prepared once.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>

#include "cli_common.h"
#include "progress.h"
#include "render_pipeline.h"
#include "uvr/core/text.h"

namespace uvr::cli {

namespace {

using Clock = std::chrono::steady_clock;

/// --steps FIRST:LAST[:STRIDE] (inclusive; either end may be left out) over `count` steps.
std::vector<std::size_t> parseSteps(const std::string& text, std::size_t count) {
    std::size_t first = 0, last = count - 1, stride = 1;
    if (!text.empty()) {
        auto number = [&](const std::string& part, std::size_t fallback) -> std::size_t {
            if (part.empty()) return fallback;
            std::size_t used = 0;
            unsigned long long v = 0;
            try {
                v = std::stoull(part, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (used != part.size() || part[0] == '-')
                throwError(ErrorKind::Argument, "",
                           "--steps " + text + ": expected FIRST:LAST[:STRIDE] of step indices");
            return static_cast<std::size_t>(v);
        };
        std::vector<std::string> parts;
        std::size_t start = 0;
        for (std::size_t colon; (colon = text.find(':', start)) != std::string::npos;
             start = colon + 1)
            parts.push_back(text.substr(start, colon - start));
        parts.push_back(text.substr(start));
        if (parts.size() < 2 || parts.size() > 3)
            throwError(ErrorKind::Argument, "",
                       "--steps " + text + ": expected FIRST:LAST[:STRIDE] of step indices");
        first = number(parts[0], 0);
        last = std::min(number(parts[1], count - 1), count - 1);
        stride = parts.size() == 3 ? number(parts[2], 1) : 1;
        if (stride == 0) throwError(ErrorKind::Argument, "", "--steps " + text + ": STRIDE is 0");
        if (first >= count || first > last)
            throwError(ErrorKind::Argument, "",
                       "--steps " + text + ": no step in it (the steps are 0 to " +
                           std::to_string(count - 1) + ")");
    }
    std::vector<std::size_t> steps;
    for (std::size_t i = first; i <= last; i += stride) steps.push_back(i);
    return steps;
}

std::string timeText(double t) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.9g", t);
    return buf;
}

std::string secondsText(double s) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.3f s", s);
    return buf;
}

}  // namespace

void addAnimateCommand(CLI::App& app, Context& ctx) {
    auto* cmd = app.add_subcommand(
        "animate",
        "Render every time step of a file or series (.pvd, a quoted 'run_*.vtu' pattern, files "
        "with time steps) to numbered PNGs in a folder; the mesh is prepared once and a step with "
        "the same points and cells only refreshes the values, while the next step is read in "
        "the background");
    auto file = std::make_shared<std::string>();
    auto folder = std::make_shared<std::string>();
    auto flags = std::make_shared<RenderFlags>();
    auto steps = std::make_shared<std::string>();
    auto prefix = std::make_shared<std::string>("frame_");
    auto perStep = std::make_shared<bool>(false);
    auto timeLabel = std::make_shared<bool>(false);
    auto movie = std::make_shared<std::string>();
    auto fps = std::make_shared<double>(10.0);
    cmd->add_option("FILE", *file,
                    "Mesh file or series: .pvd, a quoted numbered series ('run_*.vtu'), a file "
                    "with time steps, or any mesh file (one frame)")
        ->required();
    cmd->add_option("-o,--output", *folder, "Folder for the frames (created when missing)")
        ->required();
    flags->registerOn(*cmd, /*oneFrame=*/false, /*withMethod=*/true);
    cmd->add_flag("--legend", flags->legend,
                  "Draw a colour legend at the right edge of every frame (the field's name, the "
                  "colour map, ticks over the value range)");
    cmd->add_flag("--time-label", *timeLabel,
                  "Write the step's time at the top-left of every frame (\"Time: 0.5\", as "
                  "ParaView's Annotate Time)");
    cmd->add_option("--movie", *movie,
                    "Also write the frames as one animated PNG (APNG: browsers, ffmpeg and "
                    "Pillow play it; other viewers show its first frame), looping");
    cmd->add_option("--fps", *fps, "Frames per second of --movie")
        ->capture_default_str()
        ->check(CLI::Range(0.01, 1000.0));
    cmd->add_option("--steps", *steps,
                    "Steps to render, FIRST:LAST[:STRIDE] by index, inclusive (default: all)");
    cmd->add_option("--prefix", *prefix, "File name of the frames before the step's number")
        ->capture_default_str();
    cmd->add_flag("--range-per-step", *perStep,
                  "Map each frame's own step's value range (default: one range for all frames, "
                  "the union over the rendered steps, read before the first frame unless "
                  "--range gives it)");
    cmd->callback([=, &ctx] {
        applyThreads(flags->threads);
        flags->checkBeforeLoading(*file);
        checkFrameMemory(*flags, ctx);
        if (*perStep && !flags->range.empty())
            throwError(ErrorKind::Argument, "",
                       "--range-per-step and --range contradict: a given range is every "
                       "frame's");
        if (!movie->empty()) {
            if (fileExtension(*movie) != ".png")
                throwError(ErrorKind::Argument, "",
                           "--movie '" + *movie +
                               "': the movie is an animated PNG, so its name ends in .png");
            resolveOutput(*movie);
        }
        if (prefix->empty() || prefix->find('/') != std::string::npos)
            throwError(ErrorKind::Argument, "",
                       "--prefix '" + *prefix + "': expected a file name part without '/'");
        namespace fs = std::filesystem;
        std::error_code ec;
        if (fs::exists(*folder, ec) && !fs::is_directory(*folder, ec))
            throwError(ErrorKind::Argument, *folder, "-o: exists and is not a folder");
        const std::unique_ptr<MeshSeries> series = openSeries(*file, ctx);
        const std::vector<std::size_t> chosen = parseSteps(*steps, series->stepCount());
        ctx.rootWrites([&] {  // rank 0 writes the frames (data-parallel)
            fs::create_directories(*folder, ec);
            if (ec) throwError(ErrorKind::Io, *folder, "cannot create the folder: " + ec.message());
        });
        const FieldSpec spec = parseFieldSpec(flags->field);

        // Step 1: the first step read, validated and prepared.
        const auto start = Clock::now();
        ctx.setActivity(series->stepSource(chosen[0]), "reading and preparing the first step");
        if (resolvesToCuda(flags->rendererOptions().device))
            ctx.step("GPU: " + cudaDeviceDescription());
        // A new geometry of a later step is prepared in player.show (phases ended after it).
        PhaseProgress phases(ctx);
        RendererOptions options = flags->rendererOptions();
        options.communicator = ctx.comm;  // data-parallel under mpirun: each rank its piece
        SeriesPlayer player(std::unique_ptr<MeshSeries>(openSeries(*file, ctx)), spec, options,
                            chosen[0], phases.callbacks());
        phases.finish();
        for (const std::string& note : player.mesh().notes) ctx.step("note: " + note);
        Bounds3f bounds;         // of the cells that render
        if (player.byParts()) {  // each rank holds its part: the checks over every rank's
            ctx.step("read time step " + std::to_string(chosen[0]) + " by parts: each of " +
                     std::to_string(ctx.comm->size()) + " ranks reads its run of the " +
                     std::to_string(series->partCount(chosen[0])) + " " + series->partName() +
                     " of each step");
            bounds = checkShares(player.mesh(), series->stepSource(chosen[0]), ctx).bounds;
        } else {
            ValidationReport report;
            {
                Progress checking(ctx, "checking the mesh");
                report =
                    validateMesh(player.mesh(), series->stepSource(chosen[0]), checking.callback());
            }
            for (const std::string& f : report.findings()) ctx.step("validation: " + f);
            bounds = report.bounds;
        }
        if (bounds.empty())
            throwError(ErrorKind::Validation, series->stepSource(chosen[0]),
                       "no cell has volume (or the mesh has no volumetric cells): nothing to "
                       "render");
        ctx.done("read and prepared step " + std::to_string(chosen[0]) + " (" +
                     (ctx.dataParallel()
                          ? std::to_string(ctx.comm->size()) + " ranks' pieces; rank 0's: "
                          : std::string()) +
                     std::to_string(player.renderer().prepared().tets.tetCount()) +
                     " tetrahedra) of " + std::to_string(series->stepCount()),
                 start);
        std::vector<std::string> notes;
        RenderSettings settings = flags->settings(bounds, *file, &notes);
        for (const std::string& note : notes) ctx.step("note: " + note);
        validateSettings(settings);
        const std::optional<Vec3f> background = flags->backgroundColor();
        const std::optional<Font> legendFont = flags->legendFont();
        std::optional<Font> labelFont;
        if (*timeLabel) labelFont.emplace(flags->annotationFont("--time-label", "frames"));

        // Step 2: one value range for every frame (the union over the rendered steps).
        if (!settings.range && !*perStep) {
            Progress progress(ctx,
                              "reading the value range of " + std::to_string(chosen.size()) +
                                  " time steps (--range skips this)",
                              double(chosen.size()), "steps");
            float lo = INFINITY, hi = -INFINITY;
            for (std::size_t k = 0; k < chosen.size(); ++k) {
                const std::size_t i = chosen[k];
                ctx.setActivity(series->stepSource(i), "reading time step " + std::to_string(i));
                for (float v : player.stepValues(i))  // finite only (as finiteRange)
                    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
                progress.set(double(k + 1) / double(chosen.size()));
            }
            if (ctx.comm) {  // data-parallel: the union over the ranks' values
                double range[2] = {lo, -double(hi)};
                ctx.comm->allReduce(range, ReduceOp::Min);
                lo = static_cast<float>(range[0]), hi = static_cast<float>(-range[1]);
            }
            if (lo < hi) {
                settings.range = std::pair{lo, hi};
                progress.done("value range over the steps: [" + timeText(lo) + ", " + timeText(hi) +
                              "] (--range sets another)");
            } else {  // constant or no finite value: each frame as `uvr render` would draw it
                progress.done("the field has one value or none over the steps: no common range");
            }
        }

        // A reset camera keeps the volume off the legend (its columns with the first step's
        // range; one camera for every frame).
        const std::string title = legendTitle(player.field().name, player.field().association);
        LegendStyle legendStyle;
        legendStyle.background = background;
        if (legendFont && flags->cameraIsReset())
            settings.camera = cameraBesideLegend(player.renderer().prepared(), settings, bounds,
                                                 *legendFont, title);

        // Step 3: every step: values refreshed (or the new geometry prepared), rendered, written;
        // the next step read meanwhile.
        const int digits = std::max<int>(4, int(std::to_string(series->stepCount() - 1).size()));
        std::set<std::string> warned;
        std::vector<double> reads, updates, frames;
        // The movie: written frame by frame beside the PNGs, committed after the last.
        std::optional<OutputFile> movieFile;
        std::optional<ApngWriter> movieWriter;
        if (!movie->empty() && ctx.root()) {
            movieFile.emplace(*movie);
            movieWriter.emplace(*movieFile, static_cast<int>(chosen.size()), *fps);
        }
        Progress progress(ctx, "rendering " + std::to_string(chosen.size()) + " time steps",
                          double(chosen.size()), "steps");
        for (std::size_t k = 0; k < chosen.size(); ++k) {
            const std::size_t i = chosen[k];
            ctx.setActivity(series->stepSource(i), "reading time step " + std::to_string(i));
            const std::optional<std::size_t> next =
                k + 1 < chosen.size() ? std::optional(chosen[k + 1]) : std::nullopt;
            StepUpdate u;
            if (k > 0) {
                u = player.show(i, next);  // the next read overlaps this step's refresh
                phases.finish();
                reads.push_back(u.readSeconds);
                updates.push_back(u.updateSeconds);
            } else if (next) {
                player.prefetch(*next);
            }
            ctx.setActivity(*folder, "rendering time step " + std::to_string(i));
            const RenderResult result = player.renderer().render(settings);
            frames.push_back(result.stats.seconds);
            char name[64];
            std::snprintf(name, sizeof name, "%0*zu.png", digits, i);
            const std::string path = (fs::path(*folder) / (*prefix + name)).string();
            ctx.rootWrites([&] {
                Image image = result.image;
                if (legendFont)
                    drawLegend(image, *legendFont, settings.tf, result.setup.rangeLo,
                               result.setup.rangeHi, title, settings.tf.logScale, legendStyle);
                if (labelFont) {
                    LegendStyle style;
                    style.background = background;
                    drawCornerText(image, *labelFont,
                                   "Time: " + formatExact(player.series().times()[i]), style);
                }
                OutputFile out(path);
                writePng(out, image, background);
                out.finish();
                out.commit();
                if (movieWriter) movieWriter->add(image, background);
            });
            for (const std::string& note : result.setup.notes)
                if (warned.insert(note).second) ctx.warn(*file + ": " + note);
            const std::string empty =
                explainEmptyFrame(player.renderer().prepared(), settings, result);
            if (!empty.empty() && warned.insert(empty).second)
                ctx.warn(*file + ", step " + std::to_string(i) + ": " + empty);
            std::string line = "step " + std::to_string(i) + " (time " +
                               timeText(player.series().times()[i]) + "): ";
            if (k == 0)
                line += "prepared above";
            else
                line +=
                    std::string(u.rebuilt ? "new geometry prepared in " : "values refreshed in ") +
                    secondsText(u.updateSeconds) +
                    (!u.prefetched             ? ", read " + secondsText(u.readSeconds)
                     : u.readSeconds >= 0.0005 ? ", read in the background (waited " +
                                                     secondsText(u.readSeconds) + " for it)"
                                               : ", read in the background");
            line += ", frame " + secondsText(result.stats.seconds) + " -> " + path;
            ctx.step(line);
            progress.set(double(k + 1) / double(chosen.size()));
        }
        auto median = [](std::vector<double> v) {
            if (v.empty()) return 0.0;
            std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
            return v[v.size() / 2];
        };
        char summary[256];
        std::snprintf(summary, sizeof summary,
                      "wrote %zu frames to %s; per step (median): read %.3f s, update %.3f s, "
                      "frame %.3f s",
                      chosen.size(), folder->c_str(), median(reads), median(updates),
                      median(frames));
        progress.done(summary);
        ctx.rootWrites([&] {
            if (!movieWriter) return;
            movieWriter->finish();
            movieFile->finish();
            movieFile->commit();
            char line[160];
            std::snprintf(line, sizeof line, "wrote %s (%zu frames at %g per second)",
                          movie->c_str(), chosen.size(), *fps);
            ctx.step(line);
        });
    });
}

}  // namespace uvr::cli
