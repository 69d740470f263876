// SPDX-License-Identifier: MIT
#pragma once
// A render from the command line: the mesh (or its prepared cache) prepared into a Renderer,
// rendered with the flags' settings and written with the flags' outputs.

#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "cli_common.h"
#include "render_flags.h"

namespace uvr::cli {

/// Prepares `field` of a mesh into a Renderer as the flags ask, with progress messages, and
/// prints where it renders (the GPU, what was uploaded).
std::unique_ptr<Renderer> makeRenderer(const Mesh& mesh, const ScalarField& field,
                                       const RendererOptions& options, const Context& ctx);

/// A prepared mesh's source, as a render reports it: the mesh file, its summary, and the
/// prepared cache it came from (empty when prepared from the mesh).
struct RenderSource {
    std::string path;
    SourceSummary summary;
    double checkSeconds = 0.0;  ///< the mesh's check (0 from a cache)
    std::string cacheFile;
    double cacheReadSeconds = 0.0;
    /// Data-parallel: each rank's seconds to read its part of the file, in rank order.
    std::vector<double> rankReadSeconds;
};

/// Prepares, renders and writes the PNG (and stats JSON); returns the result (with --legend, its
/// image carries the legend). The mesh is taken over and freed once its cells are split.
RenderResult renderAndWrite(Mesh&& mesh, const std::string& source, const RenderFlags& flags,
                            const Context& ctx);

/// `render`'s --cache FILE and --no-cache.
struct CacheFlags {
    std::string file;  ///< --cache; empty: MESH.uvrprep when it exists
    bool off = false;  ///< --no-cache
    /// Adds the flags (exclusive) to a subcommand.
    void registerOn(CLI::App& app);
};

/// Renders from a prepared cache instead of the mesh when one applies and writes the outputs as
/// renderAndWrite does: --cache FILE (a mismatch or a damaged file is an error), else
/// MESH.uvrprep when it exists (a stale or damaged one is set aside with a warning saying why:
/// false is returned and the caller prepares from the mesh). False without a cache.
bool renderFromCache(const std::string& meshFile, const RenderFlags& flags, const StepFlags& steps,
                     const CacheFlags& cache, const Context& ctx);

/// Refuses --cache FILE for a data-parallel `command` ("render", "view"): a prepared cache is one
/// process's preparation, and each rank prepares its piece from the mesh.
void refuseCacheDataParallel(const CacheFlags& cache, const std::string& command);

/// A prepared cache found for a mesh file whose header matches what is asked for.
struct CacheMatch {
    std::string path;
    CacheKey key;  ///< the key asked for, which the arrays are read against
    bool explicitCache = false;
    std::chrono::steady_clock::time_point start;  ///< when finding it began
    /// The warning that sets a default cache aside because of `e`.
    std::string notUsing(const Error& e) const;
};

/// The prepared cache of a mesh file to use, its header read and matched (the source summary
/// goes to src): --cache FILE (a mismatch is an error), else MESH.uvrprep when it exists (a
/// stale or damaged one is set aside with a warning: nothing is returned). Nothing with
/// --no-cache. anyMethods: the cache may hold the structures of any method (the caller offers
/// the methods it holds), else those `options` asks for.
std::optional<CacheMatch> findCache(const std::string& meshFile, const RenderFlags& flags,
                                    const StepFlags& steps, const CacheFlags& cache,
                                    const RendererOptions& options, bool anyMethods,
                                    RenderSource& src, const Context& ctx);

/// Reads the arrays of a cache findCache matched (progress shown, notes and findings printed);
/// nothing when a default cache turns out damaged (warned), an error for --cache FILE.
std::optional<PreparedMesh> readCache(const CacheMatch& match, RenderSource& src,
                                      const Context& ctx);

/// A Renderer over a mesh already prepared (read from a prepared cache) on `device`; prints
/// where it renders as the other makeRenderer does.
std::unique_ptr<Renderer> makeRenderer(PreparedMesh prepared, Device device, const Context& ctx);

/// A data-parallel rank's share of a file and what the ranks agreed on about the whole mesh.
struct DistributedSource {
    MeshShare share;      ///< this rank's cells, with the field the ranks agreed on
    RenderSource source;  ///< the whole mesh's counts, bounds and checks
    /// This rank's run of the step's parts when the file is a series stored in parts (VTKHDF
    /// partitions, Exodus II cells: MeshSeries::readPart) and was read by them.
    std::optional<std::pair<std::uint64_t, std::uint64_t>> seriesParts;
};

/// Reads this rank's part of a file (a .uvrm only where the part lies, a .pvtu by runs of its
/// pieces when it has as many as ranks, any other file whole, keeping the part), agrees with
/// every rank on the field `fieldSpec` names, and reduces the counts, bounds and checks over the
/// ranks (collective; ctx.comm must be set). Throws on every rank when any rank fails. The share
/// keeps the part's fields with keepFields (shareOfPart).
DistributedSource readDistributed(const std::string& file, const std::string& fieldSpec,
                                  const StepFlags& steps, const Context& ctx,
                                  bool keepFields = false);

/// Every rank's share checked (validateMesh; collective, ctx.comm must be set): the bounds of
/// the cells that render, reduced over the ranks, and each rank's findings naming the rank,
/// shown as steps.
struct SharesChecked {
    Bounds3f bounds;
    std::vector<std::string> findings;
};
SharesChecked checkShares(const Mesh& share, const std::string& file, const Context& ctx);

/// `mpirun -n N uvr render FILE`: each rank reads its part of the file (a .uvrm only where the
/// part lies; any other file whole, keeping its part), the ranks agree on the field, the bounds
/// and the checks, render their pieces data-parallel (Renderer from a MeshShare), and rank 0
/// writes the outputs. ctx.comm must be set.
RenderResult renderDataParallel(const std::string& file, const RenderFlags& flags,
                                const StepFlags& steps, const Context& ctx);

}  // namespace uvr::cli
