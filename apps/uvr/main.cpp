// SPDX-License-Identifier: MIT
// The uvr command-line tool: info, render, demo, convert, generate, compare, bench.
#include <cstdio>
#include <new>

#include "cli_common.h"

int main(int argc, char** argv) {
    using namespace uvr;
    CLI::App app{
        "uvr: GPU-ready renderer for unstructured volume meshes (VTK .vtk/.vtu/.pvtu, "
        "native .uvrm)",
        "uvr"};
    app.require_subcommand(1);
    app.fallthrough();  // -q works after the subcommand too
    app.set_version_flag("--version", "uvr 0.1.0");
    cli::Log log;
    app.add_flag("-q,--quiet", log.quiet, "No progress messages on stderr");
    cli::addInfoCommand(app, log);
    cli::addRenderCommand(app, log);
    cli::addDemoCommand(app, log);
    cli::addConvertCommand(app, log);
    cli::addGenerateCommand(app, log);
    cli::addCompareCommand(app, log);
    cli::addBenchCommand(app, log);
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
        std::fprintf(stderr, "uvr: error: %s (see uvr --help)\n", e.what());
        return 2;
    } catch (const Error& e) {
        std::fprintf(stderr, "uvr: error: %s\n", e.what());
        return e.kind() == ErrorKind::Internal ? 70 : 2;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "uvr: error: out of memory\n");
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "uvr: internal error: %s\n", e.what());
        return 70;
    }
    return 0;
}
