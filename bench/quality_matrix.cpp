// SPDX-License-Identifier: MIT
// The evaluation matrix of issue 11 (section 5): every real mesh and two procedural ones, under
// transfer functions nobody tuned for (narrow and several bands, a step, ramps, a ParaView JSON
// export) from three views, rendered with every integrator at its defaults and measured against
// the exact integrator (SSIM, the 99.9th percentile and maximum of the per-pixel difference,
// seams and speckle of the images composited over black). Prints and writes the worst case, not
// only the median, with images of each method's worst case.
//
//   uvr_quality_matrix --data ../shared/data --out quality [--device cuda] [--size 512]
//
// Outputs in --out: cases.csv (one row per mesh, transfer function, view and method),
// summary.md (the tables docs/PERFORMANCE.md quotes), worst_<method>.png (exact | method |
// 4x difference, for the method's worst SSIM) and worst_p999_<method>.png (the same for its
// worst 99.9th percentile).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/procedural.h"
#include "uvr/render/frame_setup.h"
#include "uvr/render/image.h"
#include "uvr/render/image_metrics.h"

namespace {

using namespace uvr;

struct TfCase {
    std::string name;
    std::string colors;   ///< preset name or ParaView JSON path
    std::string opacity;  ///< opacity spec; empty: the JSON's points
};

struct ViewCase {
    std::string name;
    float azimuth, elevation;
};

struct MethodCase {
    std::string name;
    RenderMethod method;
    StepRule rule;
    bool preintegrated;
    float quality = kDefaultQuality;
};

/// The methods compared, exact first (the yardstick).
std::vector<MethodCase> kMatrixMethods = {
    {"exact", RenderMethod::Exact, StepRule::ErrorBound, true},
    // The default as every front end renders it: its rows' rendered_as says which method.
    {"auto", RenderMethod::Auto, StepRule::ErrorBound, true},
    {"reference", RenderMethod::Reference, StepRule::ErrorBound, true},
    {"adaptive", RenderMethod::Partitions, StepRule::ErrorBound, true},
    {"reference (point samples)", RenderMethod::Reference, StepRule::ErrorBound, false},
    {"adaptive (paper: variance, point samples)", RenderMethod::Partitions, StepRule::Variance,
     false},
};

const std::vector<ViewCase> kViews = {
    {"front", 0.f, 0.f}, {"oblique", 40.f, 30.f}, {"edge-on", 90.f, 5.f}};

struct Row {
    std::string mesh, tf, view, method;
    std::string renderedAs;  ///< the method that rendered (auto's pick)
    ImageComparison cmp;     ///< against the exact image (exact's own: identical)
    double ms = 0.0;
    std::uint64_t samples = 0;
    std::uint64_t visited = 0;  ///< partitions visited (sampling methods)
};

/// One mesh to evaluate: a file of the shared data or a procedural spec.
struct MeshCase {
    std::string name;
    std::string path;  ///< empty: procedural
    ProceduralSpec spec;
};

std::string csvQuote(const std::string& s) {
    return '"' + s + '"';
}

/// Exact | method | 4x absolute difference, side by side.
Image sideBySide(const Image& exact, const Image& got) {
    Image out(exact.width * 3, exact.height);
    for (int y = 0; y < exact.height; ++y)
        for (int x = 0; x < exact.width; ++x) {
            const Vec4f e = exact.at(x, y), g = got.at(x, y);
            out.at(x, y) = e;
            out.at(x + exact.width, y) = g;
            Vec4f d(std::fabs(e.x - g.x) * 4.f, std::fabs(e.y - g.y) * 4.f,
                    std::fabs(e.z - g.z) * 4.f, 1.f);
            out.at(x + 2 * exact.width, y) = d;
        }
    return out;
}

/// Keeps the items whose name is in `names` (all of them when names is empty).
template <class T>
void keepNamed(std::vector<T>& items, const std::vector<std::string>& names) {
    if (names.empty()) return;
    std::erase_if(items, [&](const T& item) {
        return std::find(names.begin(), names.end(), item.name) == names.end();
    });
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

/// The samples estimateSamples counts, split by step (at most kLongStep s1, or longer: such a
/// step locates its cell from a seed rather than walking), weighted by the partitions' box volume
/// (as auto does) or by their cells' volume; per transfer function, for fitting auto's cost model.
struct StepSplit {
    double reference = 0.0, shortSteps = 0.0, longSteps = 0.0;
};

std::vector<double> partitionCellVolumes(const PreparedMesh& pm) {
    const KdPartitions& kd = *pm.kd;
    const TetMeshView view = pm.tets.view();
    std::vector<double> out(kd.partitions.size(), 0.0);
    for (std::size_t p = 0; p < kd.partitions.size(); ++p)
        for (std::uint32_t i = 0; i < kd.partitions[p].cellCount; ++i) {
            const std::uint32_t c = kd.cells[kd.partitions[p].firstCell + i];
            Vec3f x[kMaxCellCorners];
            const int n = view.kernelGather(c, x);
            if (view.kind(c) == CellKind::Tet) {
                const Vec3f a = x[1] - x[0], b = x[2] - x[0], d = x[3] - x[0];
                out[p] += std::fabs(double(dot(a, cross(b, d)))) / 6.0;
            } else {
                Bounds3f box;
                for (int k = 0; k < n; ++k) box.extend(x[k]);
                out[p] += box.volume();
            }
        }
    return out;
}

void splitSteps(const PreparedMesh& pm, const FrameSetup& f, const std::vector<double>& weights,
                bool byBox, StepSplit& out) {
    const KdPartitions& kd = *pm.kd;
    const float s1 = f.stepRule.s1, longStep = kLongStep * s1;
    const auto add = [&](double volume, const PartitionShading& sh) {
        if (!(sh.maxOpacity > 0.f) || !(sh.step > 0.f)) return;
        (sh.step > longStep ? out.longSteps : out.shortSteps) += volume / sh.step;
    };
    for (std::size_t p = 0; p < kd.partitions.size(); ++p) {
        const double volume = byBox ? kd.partitions[p].box.volume() : weights[p];
        out.reference += volume / s1;
        const PartitionShading& sh = f.shading[p];
        if (sh.byMacroCells && !f.macroShading.empty()) {
            const PartitionGrid& g = pm.macro->grids[p];
            const std::uint32_t n = g.dims[0] * g.dims[1] * g.dims[2];
            for (std::uint32_t c = 0; c < n; ++c) add(volume / n, f.macroShading[g.first + c]);
        } else {
            add(volume, sh);
        }
    }
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "Quality matrix (issue 11): every integrator at its defaults against the exact "
        "integrator on real and procedural meshes, many transfer functions and views"};
    std::string data = "../shared/data", out = "quality", device = "cpu", tfJson;
    int size = 256, repeat = 1;
    std::uint64_t proceduralCells = 300000;
    std::vector<std::string> only;
    app.add_option("--data", data, "Folder of the real meshes")->capture_default_str();
    app.add_option("--out", out, "Output folder (created)")->capture_default_str();
    app.add_option("--device", device, "cpu or cuda")
        ->check(CLI::IsMember({"cpu", "cuda"}))
        ->capture_default_str();
    app.add_option("--size", size, "Image side in pixels")
        ->check(CLI::Range(16, 4096))
        ->capture_default_str();
    app.add_option("--repeat", repeat, "Timed frames per case (median)")
        ->check(CLI::Range(1, 100))
        ->capture_default_str();
    app.add_option("--procedural-cells", proceduralCells,
                   "Tetrahedra of each procedural mesh (about)")
        ->capture_default_str();
    app.add_option("--tf-json", tfJson,
                   "A ParaView colour-map JSON export used as one of the transfer functions")
        ->check(CLI::ExistingFile);
    app.add_option("--meshes", only, "Only these meshes (file names or procedural names)")
        ->delimiter(',');
    std::vector<float> qualities;
    app.add_option("--qualities", qualities,
                   "Also rows of the adaptive method at these --quality values")
        ->delimiter(',');
    std::uint32_t leafCells = 0;
    app.add_option("--leaf-cells", leafCells,
                   "Cells per partition (default: 1024 on the CPU, 65536 with CUDA)");
    std::vector<std::string> onlyTfs;
    app.add_option("--tfs", onlyTfs, "Only these transfer functions (names as printed)")
        ->delimiter(',');
    CLI11_PARSE(app, argc, argv);
    try {
        for (float q : qualities) {
            char name[64];
            std::snprintf(name, sizeof name, "adaptive, quality %g", double(q));
            kMatrixMethods.push_back(
                {name, RenderMethod::Partitions, StepRule::ErrorBound, true, q});
        }
        const bool cuda = device == "cuda";
        std::filesystem::create_directories(out);
        std::vector<TfCase> tfs = {
            {"ramp", "cool-to-warm", "ramp"},
            {"narrow band", "viridis", "0:0,0.49:0,0.5:1,0.51:0,1:0"},
            {"two bands", "cool-to-warm", "0:0,0.3:0,0.32:0.8,0.34:0,0.6:0,0.62:0.8,0.64:0,1:0"},
            {"five bands", "black-body",
             "0:0,0.1:0,0.11:0.6,0.12:0,0.3:0,0.31:0.6,0.32:0,0.5:0,0.51:0.6,0.52:0,0.7:0,0.71:"
             "0.6,0.72:0,0.9:0,0.91:0.6,0.92:0,1:0"},
            {"step", "grayscale", "step:0.5:0.5"},
            {"dense", "viridis", "0:0.3,1:1"},
        };
        if (!tfJson.empty()) tfs.push_back({"ParaView JSON", tfJson, ""});
        keepNamed(tfs, onlyTfs);
        std::vector<MeshCase> meshes;
        for (const char* f :
             {"bluntfin_tets.vtk", "post_tets.vtk", "spx.vtk", "post.vtk", "tetraMesh.vtk",
              "cylinder_quadratic_as_tets.vtk", "hexa.vtk", "fire_ug.vtu"}) {
            const std::string path = data + "/" + f;
            if (std::filesystem::exists(path)) meshes.push_back({f, path, {}});
        }
        ProceduralSpec multiscale;
        multiscale.targetCells = proceduralCells;
        multiscale.fields = {ProceduralField::Multiscale};
        meshes.push_back({"procedural-box-multiscale", "", multiscale});
        ProceduralSpec shell;
        shell.shape = ProceduralShape::Shell;
        shell.targetCells = proceduralCells;
        shell.fields = {ProceduralField::Jet};
        meshes.push_back({"procedural-shell-jet", "", shell});
        keepNamed(meshes, only);

        std::vector<Row> rows;
        std::map<std::string, std::pair<double, Image>> worstImage;      // method -> (ssim, image)
        std::map<std::string, std::pair<double, Image>> worstP999Image;  // method -> (p99.9, ...)
        std::map<std::string, Row> worstRow, worstP999Row;
        std::ofstream estimates(out + "/estimates.csv");
        estimates << "mesh,transfer_function,box_reference,box_short,box_long,cells_reference,"
                     "cells_short,cells_long\n";
        for (const MeshCase& mc : meshes) {
            const Mesh mesh = mc.path.empty() ? generateMesh(mc.spec) : readMesh(mc.path);
            const ScalarField field = selectScalarField(mesh, {});
            PrepareOptions o;
            if (cuda) {
                o.lbvh = buildLbvhCuda;
                o.kdSplitter = buildKdTreeCuda;
                o.builderMinTets = 4000000;
                o.kd.leafCells = 65536;  // the CLI's CUDA default
            }
            if (leafCells) o.kd.leafCells = leafCells;
            const PreparedMesh pm = prepareMesh(mesh, field, o);
            std::unique_ptr<CudaScene> gpu;
            if (cuda) gpu = std::make_unique<CudaScene>(pm);
            std::printf("%s: %zu tetrahedra, field %s, %zu partitions\n", mc.name.c_str(),
                        pm.tets.tets.size(), field.name.c_str(), pm.kd->partitions.size());
            std::fflush(stdout);
            const std::vector<double> cellVolumes = partitionCellVolumes(pm);
            for (const TfCase& tc : tfs)
                for (const ViewCase& vc : kViews) {
                    if (&vc == &kViews[0]) {  // auto's estimate: per transfer function
                        RenderSettings e;
                        e.width = e.height = 16;
                        e.tf = loadTransferFunction(tc.colors);
                        if (!tc.opacity.empty()) applyOpacitySpec(e.tf, tc.opacity);
                        e.method = RenderMethod::Partitions;
                        const FrameSetup f = makeFrameSetup(pm, e, /*gpu=*/false);
                        StepSplit box, cells;
                        splitSteps(pm, f, cellVolumes, true, box);
                        splitSteps(pm, f, cellVolumes, false, cells);
                        estimates << csvQuote(mc.name) << ',' << csvQuote(tc.name) << ','
                                  << box.reference << ',' << box.shortSteps << ',' << box.longSteps
                                  << ',' << cells.reference << ',' << cells.shortSteps << ','
                                  << cells.longSteps << '\n';
                    }
                    RenderSettings s;
                    s.width = s.height = size;
                    s.tf = loadTransferFunction(tc.colors);
                    if (!tc.opacity.empty()) applyOpacitySpec(s.tf, tc.opacity);
                    s.camera =
                        orbitCamera(resetCamera(mesh.bounds(), 1.f), vc.azimuth, vc.elevation);
                    Image exact;
                    Rgb8Image exact8;
                    for (const MethodCase& mcase : kMatrixMethods) {
                        s.method = mcase.method;
                        s.stepRule = mcase.rule;
                        s.preintegrated = mcase.preintegrated;
                        s.quality = mcase.quality;
                        std::vector<double> times;
                        RenderResult r;
                        const int frames = mcase.method == RenderMethod::Exact ? 1 : repeat;
                        for (int i = 0; i < frames + (cuda ? 1 : 0); ++i) {  // GPU: warm up
                            r = cuda ? gpu->render(s) : renderCpu(pm, s);
                            if (!cuda || i > 0) times.push_back(r.stats.seconds);
                        }
                        Row row;
                        row.mesh = mc.name, row.tf = tc.name, row.view = vc.name;
                        row.method = mcase.name;
                        row.renderedAs = methodName(r.setup.method.method);
                        row.ms = median(times) * 1e3;
                        row.samples = r.stats.samples;
                        row.visited = r.stats.partitionsVisited;
                        if (mcase.method == RenderMethod::Exact) {
                            exact = r.image;
                            exact8 = toRgb8(exact);
                            row.cmp.ssim = 1.0;
                            row.cmp.psnr = INFINITY;
                        } else {
                            const ImageComparison c = compareImages(exact8, toRgb8(r.image));
                            row.cmp = c;
                            auto it = worstImage.find(mcase.name);
                            if (it == worstImage.end() || c.ssim < it->second.first) {
                                worstImage[mcase.name] = {c.ssim, sideBySide(exact, r.image)};
                                worstRow[mcase.name] = row;
                            }
                            auto ip = worstP999Image.find(mcase.name);
                            if (ip == worstP999Image.end() || c.p999Difference > ip->second.first) {
                                worstP999Image[mcase.name] = {c.p999Difference,
                                                              sideBySide(exact, r.image)};
                                worstP999Row[mcase.name] = row;
                            }
                        }
                        rows.push_back(row);
                    }
                    std::printf("  %-12s %-8s", tc.name.c_str(), vc.name.c_str());
                    for (std::size_t i = rows.size() - kMatrixMethods.size() + 1; i < rows.size();
                         ++i)
                        std::printf(" %.4f/%g/%.3gms%s%s", rows[i].cmp.ssim,
                                    rows[i].cmp.p999Difference, rows[i].ms,
                                    rows[i].method == "auto" ? ":" : "",
                                    rows[i].method == "auto" ? rows[i].renderedAs.c_str() : "");
                    std::printf("\n");
                    std::fflush(stdout);
                }
        }

        // cases.csv
        {
            std::ofstream csv(out + "/cases.csv");
            csv << "mesh,transfer_function,view,method,rendered_as,ssim_vs_exact,psnr,ms_per_frame,"
                   "samples,partitions_visited";
            for (const ComparisonField& f : differenceFields(ImageComparison{}))
                csv << ',' << f.name;
            csv << '\n';
            for (const Row& r : rows) {
                csv << csvQuote(r.mesh) << ',' << csvQuote(r.tf) << ',' << r.view << ','
                    << csvQuote(r.method) << ',' << r.renderedAs << ',' << r.cmp.ssim << ','
                    << r.cmp.psnr << ',' << r.ms << ',' << r.samples << ',' << r.visited;
                for (const ComparisonField& f : differenceFields(r.cmp)) csv << ',' << f.value;
                csv << '\n';
            }
        }
        // summary.md: per method the worst and median SSIM, the cases under 0.98, the worst
        // case, the worst 99.9th percentile and maximum of the per-pixel difference, the cases
        // with seams and the case of the worst percentile; per mesh the worst SSIM of each method
        // and the median speed-up over the reference.
        std::ostringstream md;
        md << "Device: " << (cuda ? cudaDeviceDescription() : "CPU") << "; " << size << "x" << size
           << " pixels; " << meshes.size() << " meshes x " << tfs.size() << " transfer functions x "
           << kViews.size()
           << " views; SSIM, the 99.9th percentile and maximum of the per-pixel difference (8-bit "
              "levels) and seams against the exact integrator, composited over black.\n\n";
        md << "| method | worst SSIM | median SSIM | cases < 0.98 | worst case | worst p99.9 | "
              "worst max | cases with seams | worst p99.9 case |\n"
              "|---|---|---|---|---|---|---|---|---|\n";
        for (std::size_t m = 1; m < kMatrixMethods.size(); ++m) {
            std::vector<double> ssims;
            int below = 0, seamed = 0;
            double worstMax = 0.0;
            for (const Row& r : rows)
                if (r.method == kMatrixMethods[m].name) {
                    ssims.push_back(r.cmp.ssim);
                    below += r.cmp.ssim < 0.98;
                    seamed += r.cmp.seamCount > 0;
                    worstMax = std::max(worstMax, r.cmp.maxAbsDifference);
                }
            const Row& w = worstRow[kMatrixMethods[m].name];
            const Row& wp = worstP999Row[kMatrixMethods[m].name];
            char line[1024];
            std::snprintf(line, sizeof line,
                          "| %s | %.4f | %.4f | %d of %zu | %s, %s, %s | %g | %g | %d | %s, %s, "
                          "%s |\n",
                          kMatrixMethods[m].name.c_str(), w.cmp.ssim, median(ssims), below,
                          ssims.size(), w.mesh.c_str(), w.tf.c_str(), w.view.c_str(),
                          wp.cmp.p999Difference, worstMax, seamed, wp.mesh.c_str(), wp.tf.c_str(),
                          wp.view.c_str());
            md << line;
        }
        // Per mesh: the worst SSIM of each method, then each method's median time and the
        // median speed-up of the others over the reference (row order is kMatrixMethods' per case).
        const std::size_t nm = kMatrixMethods.size();
        md << "\n| mesh |";
        for (std::size_t m = 1; m < nm; ++m)
            md << " worst SSIM: " << kMatrixMethods[m].name << " |";
        for (std::size_t m = 0; m < nm; ++m) md << " ms: " << kMatrixMethods[m].name << " |";
        for (std::size_t m = 2; m < nm; ++m) md << " speed-up: " << kMatrixMethods[m].name << " |";
        md << "\n|---|";
        for (std::size_t m = 1; m < 3 * nm - 2; ++m) md << "---|";
        md << "\n";
        for (const MeshCase& mc : meshes) {
            std::vector<double> worst(nm, 1.0);
            std::vector<std::vector<double>> ms(nm), speedup(nm);
            for (std::size_t i = 0; i + nm <= rows.size(); i += nm) {
                if (rows[i].mesh != mc.name) continue;
                for (std::size_t m = 0; m < nm; ++m) {
                    worst[m] = std::min(worst[m], rows[i + m].cmp.ssim);
                    ms[m].push_back(rows[i + m].ms);
                    speedup[m].push_back(rows[i + 1].ms / std::max(rows[i + m].ms, 1e-6));
                }
            }
            md << "| " << mc.name << " |";
            char cell[32];
            for (std::size_t m = 1; m < nm; ++m) {
                std::snprintf(cell, sizeof cell, " %.4f |", worst[m]);
                md << cell;
            }
            for (std::size_t m = 0; m < nm; ++m) {
                std::snprintf(cell, sizeof cell, " %.2f |", median(ms[m]));
                md << cell;
            }
            for (std::size_t m = 2; m < nm; ++m) {
                std::snprintf(cell, sizeof cell, " %.2fx |", median(speedup[m]));
                md << cell;
            }
            md << "\n";
        }
        {
            std::ofstream f(out + "/summary.md");
            f << md.str();
        }
        std::printf("\n%s", md.str().c_str());
        for (const auto& [name, w] : worstImage) {
            std::string file = name;
            for (char& c : file)
                if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.') c = '_';
            writePng(out + "/worst_" + file + ".png", w.second, Vec3f(0.f, 0.f, 0.f));
            writePng(out + "/worst_p999_" + file + ".png", worstP999Image.at(name).second,
                     Vec3f(0.f, 0.f, 0.f));
        }
        return 0;
    } catch (const Error& e) {
        std::fprintf(stderr, "uvr_quality_matrix: %s\n", e.what());
        return 2;
    }
}
