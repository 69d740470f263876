// SPDX-License-Identifier: MIT
// The uvr command-line tool: info, render, demo, convert, generate, refine, compare, bench,
// presets.
#include <cstdio>
#include <new>

#include "cli_common.h"
#include "parse_errors.h"
#include "uvr/core/text.h"
#include "uvr/core/version.h"

int main(int argc, char** argv) {
    using namespace uvr;
    // Ctrl-C or a kill leaves no temporary output behind; a closed pipe is a write error.
    installOutputSignalHandlers();
    CLI::App app{
        "uvr: GPU-ready renderer for unstructured volume meshes (VTK .vtk/.vtu/.pvtu/.vtkhdf, "
        "Exodus II .e/.exo/.ex2, ParaView .pvd series, numbered series 'run_*.vtu', native "
        ".uvrm)",
        "uvr"};
    app.require_subcommand(1);
    app.fallthrough();  // -q works after the subcommand too
    app.set_version_flag("--version", std::string("uvr ") + kVersion);
    cli::Context ctx;
    ctx.app = &app;
    app.add_flag("-q,--quiet", ctx.quiet, "No progress messages on stderr");
    std::string maxMemory;
    const cli::MemoryDefault memoryDefault = cli::defaultMaxMemory();
    app.add_option("--max-memory", maxMemory,
                   "Memory limit, e.g. 16G (default: 80% of physical memory, here " +
                       memoryDefault.how +
                       "): the most a file load holds in all (its arrays, pieces and file "
                       "buffers), and the estimated image buffers of --size and meshes of "
                       "--cells; larger needs are refused before allocating");
    app.parse_complete_callback([&] {
        // mpirun: one rank per process, data-parallel; `render`, `view`, `animate` and `bench`
        // divide their work.
        if (ctx.dataParallel())
            for (const CLI::App* sub : app.get_subcommands())
                if (sub->get_name() != "render" && sub->get_name() != "bench" &&
                    sub->get_name() != "animate" && sub->get_name() != "view")
                    throwError(ErrorKind::Unsupported, "",
                               "uvr " + sub->get_name() +
                                   " does not run data-parallel: run it without mpirun "
                                   "(`mpirun -n N uvr render`, `view`, `animate` and `bench` "
                                   "do)");
        cli::capEnvironmentThreads();
        ctx.maxMemoryBytes =
            maxMemory.empty() ? memoryDefault.bytes : cli::parseBytes("--max-memory", maxMemory);
        if (maxMemory.empty()) ctx.maxMemoryDefault = memoryDefault.how;
    });
    cli::addInfoCommand(app, ctx);
    cli::addRenderCommand(app, ctx);
    cli::addPrepareCommand(app, ctx);
    cli::addDemoCommand(app, ctx);
    cli::addConvertCommand(app, ctx);
    cli::addGenerateCommand(app, ctx);
    cli::addRefineCommand(app, ctx);
    cli::addCompareCommand(app, ctx);
    cli::addBenchCommand(app, ctx);
    cli::addPresetsCommand(app, ctx);
    cli::addViewCommand(app, ctx);
    cli::addAnimateCommand(app, ctx);
    // Started by mpirun (or srun): the ranks render data-parallel, and only rank 0 writes
    // messages and files; every rank agrees on failures, so all exit with rank 0's message.
    try {
        if (launchedUnderMpi()) {
            pinGpuToLocalRank();  // one GPU per rank of a node, before CUDA starts
            ctx.comm = &mpiWorld();
        }
    } catch (const Error& e) {
        std::fprintf(stderr, "uvr: error: %s\n", printable(e.what()).c_str());
        return 2;
    }
    const bool root = ctx.root();
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::RuntimeError& e) {
        return e.get_exit_code();  // a completed command's own exit status (compare --min-ssim)
    } catch (const CLI::ParseError& e) {
        const std::vector<std::string> args(argv + 1, argv + argc);
        if (root)
            std::fprintf(stderr, "uvr: error: %s\n",
                         printable(cli::describeParseError(app, args, e)).c_str());
        return 2;
    } catch (const Error& e) {
        // The library names settings in neutral words: here, by their flags (--max-sample-distance
        // -2:
        // ...). Messages quote names from files: escaped, they stay one line.
        if (root) std::fprintf(stderr, "uvr: error: %s\n", printable(ctx.spell(e)).c_str());
        return e.kind() == ErrorKind::Internal ? 70 : 2;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "uvr: error: %s\n", printable(ctx.outOfMemoryMessage()).c_str());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "uvr: internal error: %s\n", printable(e.what()).c_str());
        return 70;
    }
    return 0;
}
