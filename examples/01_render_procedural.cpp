// SPDX-License-Identifier: MIT
// Example 1: generate a procedural tetrahedral mesh, render it with the CPU reference marcher and
// write a PNG. Usage: 01_render_procedural [OUT.png]
#include <cstdio>

#include "uvr/uvr.h"

int main(int argc, char** argv) {
    const char* out = argc > 1 ? argv[1] : "01_render_procedural.png";
    try {
        uvr::ProceduralSpec spec;  // a jittered box with a turbulent jet field
        spec.targetCells = 20000;
        const uvr::Mesh mesh = uvr::generateMesh(spec);
        const uvr::ScalarField field = uvr::selectScalarField(mesh, uvr::parseFieldSpec("jet"));
        uvr::RendererOptions options;  // prepared once; any number of frames
        options.device = uvr::Device::Cpu;
        uvr::Renderer renderer(mesh, field, options);

        uvr::RenderSettings settings;
        settings.method = uvr::RenderMethod::Reference;
        settings.width = 256;
        settings.height = 256;
        settings.tf = uvr::transferFunctionPreset("black-body");
        uvr::applyOpacitySpec(settings.tf, "0:0,0.3:0.05,1:1");
        const uvr::RenderResult result = renderer.render(settings);
        uvr::writePng(out, result.image, uvr::Vec3f(0.1f, 0.1f, 0.12f));
        std::printf("%s: %llu samples, %.1f per pixel, %.3f s\n", out,
                    static_cast<unsigned long long>(result.stats.samples),
                    result.stats.meanSamplesPerPixel(), result.stats.seconds);
    } catch (const uvr::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
