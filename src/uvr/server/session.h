// SPDX-License-Identifier: MIT
#pragma once

#include <list>
#include <string>
#include <string_view>

#include "server_internal.h"
#include "uvr/server/view_state.h"

namespace uvr::server {

/// One WebSocket connection: a browser tab's state and its outgoing messages. Lives on the
/// network thread; the render thread reads and writes the fields under Impl::m.
class Session : public std::enable_shared_from_this<Session> {
public:
    Session(ViewServer::Impl& server, tcp::socket&& socket)
        : server_(server), ws_(std::move(socket)), writeTimer_(ws_.get_executor()) {}

    // State shared with the render thread, guarded by Impl::m.
    ViewState state;
    std::uint64_t seq = 0;
    FrameDemand demand;        ///< what the tab asks of the render thread (frame_scheduler.h)
    bool resetRange = false;   ///< the field changed without a range: use the field's
    std::string histogramKey;  ///< the field whose histogram the tab has (Impl::fieldKey)
    std::string peer;
    void start(http::request<http::string_body> req);

    /// Queues a text message (network thread). With `supersedes` (its type: "state", "export",
    /// "histogram", "progress"), it replaces a message of that type still waiting: a tab that
    /// reads slowly gets the newest of each, not every one.
    void sendText(std::string text, std::string_view supersedes = {});
    /// Queues a frame's description and image; the frame ends when its image is written
    /// (network thread).
    void sendImage(std::string meta, std::string bytes);
    /// Ends the connection at once (the server shuts down; network thread): the page sees the
    /// socket close and says the connection was lost.
    void shutdown();

    /// Queues an `error` answering `request`, its message cut to kMaxErrorBytes.
    void sendError(const std::string& message, const std::string& request);

private:
    struct Out {
        bool binary;
        std::string data;
        bool endsFrame;
        std::string_view kind;  ///< the type a newer message replaces it for, or empty
    };
    void onAccept(beast::error_code ec);
    std::size_t liveSessionsLocked();
    std::string endpointName();
    void doRead();
    void onRead(beast::error_code ec);

    /// Token bucket of maxMessagesPerSecond: false (and one error a second) when over.
    bool admit();
    void handle(const std::string& text);

    /// Answers a refused request: the error (with the request's seq, when it had one) and, for a
    /// state change, the state as it stays, so that the page can show it again.
    void refused(const std::string& message, const std::string& type, const Json& msg);

    /// Checks the keys every state change may carry (seq, interactive) before anything changes.
    static void checkChangeKeys(const Json& msg);

    /// Records a change of the state (under Impl::m; checkChangeKeys passed).
    void markChanged(const Json& msg);
    void onSet(const Json& msg);
    void onResetCamera(const Json& msg);
    void onPing(const Json& msg);
    void onSnapshot();
    void onExport();
    void sendState();

    /// Queues a message: at most kMaxOutbox messages and opt.maxQueuedBytes of text wait (a
    /// tab has at most one frame's image queued: the render thread waits for it to be sent);
    /// past either the connection counts as not reading and is closed. The first message of
    /// an empty queue always goes.
    void queue(bool binary, std::string data, bool endsFrame, std::string_view kind = {});
    void pump();
    void onWrite(beast::error_code ec);
    void frameDone();
    ViewServer::Impl& server_;
    websocket::stream<beast::tcp_stream> ws_;
    beast::flat_buffer buffer_;
    net::steady_timer writeTimer_;  ///< runs while a write is under way
    std::list<Out> outbox_;         ///< a list: the front being written stays put when others go
    std::size_t queuedTextBytes_ = 0;
    bool writing_ = false;
    bool closed_ = false;
    double tokens_ = 1e9;  // capped at the rate on first use
    Clock::time_point lastRefill_ = Clock::now();
    Clock::time_point lastDropReport_{};
    std::uint64_t dropped_ = 0;
};

}  // namespace uvr::server
