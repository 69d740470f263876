// SPDX-License-Identifier: MIT
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "uvr/cache/prepared_cache.h"
#include "uvr/facade/renderer.h"
#include "uvr/mesh/io/time_series.h"
#include "uvr/mesh/mesh.h"
#include "uvr/server/view_state.h"

namespace uvr::server {

/// The range of ServerOptions::targetFrameMs.
inline constexpr double kMinTargetFrameMs = 5.0, kMaxTargetFrameMs = 1000.0;

/// How the viewer's server listens and what it allows (docs/VIEWER.md).
struct ServerOptions {
    std::string host = "127.0.0.1";  ///< address to listen on (localhost by default)
    std::uint16_t port = 8080;       ///< 0: any free port (port() tells which)
    /// The secret every request must carry; empty: 32 random hexadecimal characters. Given
    /// tokens need kMinTokenLength or more characters from [A-Za-z0-9_-].
    std::string token;
    std::size_t maxMessageBytes = 4u << 20;  ///< larger WebSocket messages close the connection
    int maxMessagesPerSecond = 200;          ///< per connection; more are dropped with an error
    int maxSessions = 32;                    ///< WebSocket connections at once
    /// TCP connections at once (page requests and WebSockets, with or without a token; fewer
    /// when the descriptor limit is lower): one more closes the oldest that has not become a
    /// WebSocket, or is closed itself.
    int maxConnections = 128;
    /// Text bytes waiting to be sent to one WebSocket connection (beyond at most one frame):
    /// a connection that does not read past this is closed.
    std::size_t maxQueuedBytes = 8u << 20;
    /// An HTTP connection waiting this long for a request (idle, without a token too) is closed.
    double idleSeconds = 30.0;
    /// A WebSocket connection whose write has waited this long (the tab does not read) is closed.
    double stalledWriteSeconds = 30.0;
    /// Reduced-resolution frames aim at this render time, in [kMinTargetFrameMs,
    /// kMaxTargetFrameMs] (`uvr view --moving-frame-ms`): 30 suits a GPU (about 30 updates a
    /// second); a CPU gets sharper moving frames at fewer updates from 50 or more.
    double targetFrameMs = 30.0;
    int refineDelayMs = 150;  ///< full resolution once the state has been still this long
    int maxScale = 8;         ///< coarsest reduced resolution: 1/maxScale of each side
    int jpegQuality = 80;     ///< of reduced-resolution frames
};

/// Shortest token ServerOptions::token may be.
inline constexpr std::size_t kMinTokenLength = 16;

/// Checks the options before any work (a given token's form, the limits, the host's form) and,
/// with tryAddress, that the address can be bound now (another server on the port fails here,
/// not after minutes of reading); throws Error(Argument) or Error(Io) naming the flag or address.
void checkServerOptions(const ServerOptions& options, bool tryAddress);

/// What the server shows: the mesh as read (kept for field changes), how to prepare it, the
/// render settings the command line fixed and the state every new tab starts from.
struct ViewScene {
    std::string file;  ///< as named on the command line
    /// The mesh as read (the server replaces its fields when a tab shows another time step);
    /// null when served from a prepared cache (fromCache).
    std::shared_ptr<Mesh> mesh;
    /// The time steps of `file` (a series opened on it) when it has more than one; `mesh` holds
    /// step initial.step. Steps must share the mesh's points and cells.
    std::shared_ptr<MeshSeries> series;
    Bounds3f bounds;                  ///< of the rendered cells, in file coordinates
    RendererOptions rendererOptions;  ///< how fields are prepared
    RenderSettings base;              ///< steps, sampling and rules beyond the state
    ViewState initial;                ///< every tab's starting state
    /// Prepared for initial.field (the command line's preparation, with its progress); null:
    /// prepared before the first frame.
    std::unique_ptr<Renderer> renderer;
    /// Data-parallel from the file's parts (`uvr view` under mpirun, readDistributed): `mesh` is
    /// this rank's part (its cells and the points they use, with every field), and these are
    /// their ids in the whole mesh and the whole mesh's counts. The fields' ranges, which hold
    /// one value, the histograms and the cell kinds are reduced over the ranks, and the
    /// renderer is made from the part (Renderer(MeshShare)). None: `mesh` is the whole mesh.
    struct Part {
        std::vector<std::uint64_t> pointIds, cellIds;
        std::uint64_t points = 0, cells = 0;
        /// A series (`series` set): this rank's run of each step's parts (MeshSeries::readPart),
        /// a step's fields read from those.
        std::optional<std::pair<std::uint64_t, std::uint64_t>> steps;
    };
    std::optional<Part> part;
    /// A scene served from a prepared cache (`uvr view` with MESH.uvrprep): no mesh was read,
    /// so `renderer` (set) serves the one field it was prepared for, with no other field and
    /// no time steps, and the page offers the methods it holds (renderableMethods).
    struct FromCache {
        std::string file;       ///< the cache
        std::string fieldSpec;  ///< the `--field` it was prepared for ("" the default)
        SourceSummary summary;  ///< the mesh's counts and the field's name
    };
    std::optional<FromCache> fromCache;
    std::vector<std::string> notes;  ///< validation findings and notes the page shows
    double loadSeconds = 0.0;        ///< reading the file
    /// Flags of the command line that shape the image beyond the state (--sample-distance,
    /// --sampling, ...) for the exported `uvr render` command, each a separate argument.
    std::vector<std::string> commandFlags;
    /// The image size was given (--size): the page keeps it; otherwise it renders at the size
    /// of its view on the screen (info's `fit_size`), which on a CPU is most of the speed.
    bool sizeGiven = false;
};

/// Log lines of the server (connections, preparations, failures), one line each.
using LogFn = std::function<void(const std::string&)>;

/// The viewer's HTTP + WebSocket server (Boost.Beast): serves the page embedded from web/,
/// keeps one state per WebSocket connection over the one prepared mesh, and renders the newest
/// state of each connection on one render thread (latest wins; docs/VIEWER.md).
class ViewServer {
public:
    /// Checks the options (a given token's form) and takes the scene; throws Error(Argument).
    ViewServer(ViewScene scene, ServerOptions options, LogFn log = {});
    /// Stops the server if it runs.
    ~ViewServer();
    ViewServer(const ViewServer&) = delete;
    ViewServer& operator=(const ViewServer&) = delete;

    /// Binds and starts serving on background threads; throws Error(Io) naming the address
    /// when it cannot listen there.
    void start();
    /// The port it listens on (after start).
    std::uint16_t port() const;
    /// The token.
    const std::string& token() const;
    /// The address to open: http://HOST:PORT/?token=TOKEN.
    std::string url() const;
    /// Serves until stop() or, with handleSignals, SIGINT or SIGTERM; then shuts down.
    void run(bool handleSignals = true);
    /// Asks a running server to stop (any thread).
    void stop();
    /// Data-parallel (scene.rendererOptions.communicator of several ranks), on every rank but
    /// 0: mirrors the renderer calls of rank 0's server (each field it prepares or switches to,
    /// each frame it renders, the ranks' pieces composited onto rank 0) until rank 0's server
    /// stops. Every rank makes its ViewServer from the same scene; only rank 0 serves.
    void follow();

    /// The server's inside (server_internal.h); opaque.
    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace uvr::server
