// SPDX-License-Identifier: MIT
#pragma once
// The viewer's server inside: ViewServer::Impl, shared by view_server.cpp (the
// accept loop, the render thread, start and stop), session.cpp (one WebSocket connection) and
// http_connection.cpp (one HTTP connection).

// Boost 1.74's asio/awaitable.hpp uses std::exchange without including <utility>.
#include <utility>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "uvr/dist/communicator.h"
#include "uvr/server/frame_scheduler.h"
#include "uvr/server/view_frame.h"
#include "uvr/server/view_server.h"

namespace uvr::server {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Json = nlohmann::json;

/// Longest error message sent to a page (a message quoting a client's value is cut).
inline constexpr std::size_t kMaxErrorBytes = 512;

/// A duration of `s` seconds for timers.
inline Clock::duration seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

/// What the server knows of a field once a tab has shown it: its finite range and histogram.
struct FieldEntry {
    std::pair<float, float> range{0.f, 1.f};
    Json histogram;
};

class Session;
class HttpConnection;

struct ViewServer::Impl {
    ViewScene scene;
    ServerOptions opt;
    LogFn log;
    std::vector<FieldInfo> fieldInfos;
    Json infoBase;  ///< the parts of `info` every connection gets (under m once serving)

    net::io_context ioc{1};
    tcp::acceptor acceptor{ioc};
    // Network thread only: the HTTP connections (oldest first), the connection cap in force,
    // and the accept loop's backoff after failures.
    std::deque<std::weak_ptr<HttpConnection>> httpConnections;
    int connectionCap = 0;
    net::steady_timer acceptRetry{ioc};
    std::chrono::milliseconds acceptDelay{0};
    std::uint64_t acceptFailures = 0;
    Clock::time_point lastAcceptLog{};
    std::optional<net::signal_set> signals;
    std::thread ioThread, renderThread;
    std::uint16_t boundPort = 0;
    bool started = false;

    // Shared between the network thread and the render thread.
    std::mutex m;
    std::condition_variable cv;
    bool stopping = false;
    std::vector<std::weak_ptr<Session>> sessions;
    std::size_t roundRobin = 0;
    std::map<std::string, FieldEntry> fields;  ///< by fieldKey; filled by the render thread
    std::mutex fieldsMutex;                    ///< guards `fields` against info's readers
    /// The one prepared mesh (render thread): prepared for the field of rendererKey; another
    /// field's values replace them without rebuilding geometry (Renderer::setFieldValues).
    std::unique_ptr<Renderer> renderer;
    std::string rendererKey;

    void say(const std::string& line) const {
        if (log) log(line);
    }
    /// Canonical key of a field spec at a time step (the field's index and component, the
    /// step), or throws Error(Argument) for a spec naming no field.
    std::string fieldKey(const std::string& spec, std::size_t step = 0) const {
        const FieldSpec fs = parseFieldSpec(spec);
        const FieldChoice c = resolveField(fieldInfos, fs);
        return std::to_string(c.index) + ":" + std::to_string(fs.component) + "@" +
               std::to_string(step);
    }
    /// The field a spec names on this rank's mesh, chosen by the listed fields (fieldInfos:
    /// with the whole mesh's constancy when the ranks hold parts, so every rank picks alike).
    ScalarField valuesOf(const std::string& spec) const;
    /// A field's finite range and histogram: over every rank's part (collective) when the ranks
    /// hold parts (scene.part), else over `values`.
    FieldEntry entryOf(const std::vector<float>& values) const;
    /// Time steps of the file (1 without a series).
    std::size_t stepCount() const { return scene.series ? scene.series->stepCount() : 1; }
    /// The time step whose fields scene.mesh holds (render thread).
    std::size_t meshStep = 0;
    /// Makes the renderer hold the field's values at a time step (preparing the mesh the first
    /// time, else reading the step's fields when it is another and replacing the values) and
    /// returns the field's entry (render thread). `progress` reports the preparation's steps.
    FieldEntry field(const std::string& spec, std::size_t step, const ProgressFn& progress);
    void acceptLoop();
    /// Handles a failed accept: closes the oldest HTTP connection when descriptors ran out, and
    /// accepts again after a delay that doubles with each failure in a row (up to
    /// kAcceptRetryMax), saying so in the log at most every kAcceptLogInterval.
    void acceptFailed(const beast::error_code& ec);
    /// Takes a new TCP connection: over the cap, closes the oldest HTTP connection to make room,
    /// or the new one when all are WebSockets (network thread).
    void admitConnection(tcp::socket socket);
    /// Closes the oldest live HTTP connection (network thread); false when there is none.
    bool closeOldestHttp();
    void renderLoop();
    /// Sends a text message to every connection (any thread); `supersedes` as Session::sendText.
    void broadcast(const std::string& text, std::string_view supersedes = {});
    /// Prepares the starting field before the first frame when the scene came without a
    /// renderer (render thread): every connection sees the steps as `progress` and the result
    /// as `prepared`, and later connections get it in `info`.
    void prepareAtStart();
    void requestStop();
    Json exportMessage(const ViewState& s) const;

    /// Data-parallel: the ranks when there are several (scene.rendererOptions.communicator),
    /// else null.
    Communicator* ranks() const;
    /// Data-parallel, on rank 0: sends every other rank the renderer call it is about to make
    /// (follow() makes the same call there); nothing otherwise.
    void lead(const Json& call);
    /// Data-parallel, on rank 0: tells the other ranks to stop following (once).
    void releaseFollowers();
    bool followersReleased = false;
    /// The frame of `state` as renderViewFrame renders it, on every rank (render thread).
    ViewFrame frame(const ViewState& state, FrameKind kind, int scale, std::uint64_t seq,
                    const FrameEncoding& encoding);
};

}  // namespace uvr::server
