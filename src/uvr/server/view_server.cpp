// SPDX-License-Identifier: MIT
#include "uvr/server/view_server.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <list>
#include <map>
#include <mutex>
#include <random>
#include <thread>

#include "uvr/core/error.h"
#include "uvr/core/text.h"
#include "uvr/facade/frame_report.h"
#include "uvr/mesh/cell_types.h"
#include "uvr/render/heatmap.h"
#include "uvr/render/image.h"
#include "uvr/render/settings_vocabulary.h"
#include "uvr/server/frame_codec.h"
#include "uvr/server/frame_scheduler.h"
#include "uvr/server/view_frame.h"
#include "uvr/server/web_assets.h"
#include "uvr/tf/transfer_function.h"

namespace uvr::server {

namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Json = nlohmann::json;

/// Bins of the field histograms the page draws.
constexpr int kHistogramBins = 256;
/// Messages waiting to be written to one connection before it counts as not reading.
constexpr std::size_t kMaxOutbox = 256;
/// Longest error message sent to a page (a message quoting a client's value is cut).
constexpr std::size_t kMaxErrorBytes = 512;
/// Descriptors kept free of connections below the process's limit (files of time steps, the
/// log, the render thread's needs).
constexpr int kReservedDescriptors = 32;
/// The first and longest wait before accepting again after accept failed (EMFILE: no
/// descriptor left), and the least time between two log lines about it.
constexpr auto kAcceptRetryFirst = std::chrono::milliseconds(10);
constexpr auto kAcceptRetryMax = std::chrono::milliseconds(1000);
constexpr auto kAcceptLogInterval = std::chrono::seconds(10);

/// A duration of `s` seconds for timers.
Clock::duration seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

std::string fmtSeconds(double s) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", s);
    return buf;
}

double secondsSince(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

/// Least time between two "progress" messages of a phase with fractions.
constexpr double kProgressInterval = 0.1;

/// A preparation's progress as "progress" messages given to `send`: each phase's name with
/// fraction null when it starts (`onStep` hears the name first, when set), then its fractions
/// at most every kProgressInterval seconds and its end (1) always. Callable from any thread.
ProgressFn progressMessages(std::function<void(const std::string&)> send,
                            std::function<void(const std::string&)> onStep = {}) {
    struct Phase {
        std::mutex m;
        std::string name;
        Clock::time_point last;
    };
    auto phase = std::make_shared<Phase>();
    auto message = [](const std::string& name, const Json& fraction) {
        return Json{{"type", "progress"}, {"phase", name}, {"fraction", fraction}}.dump(
            -1, ' ', false, Json::error_handler_t::replace);
    };
    return {[=](const std::string& name) {
                if (onStep) onStep(name);
                {
                    std::lock_guard lk(phase->m);
                    phase->name = name;
                    phase->last = Clock::now();
                }
                send(message(name, nullptr));
            },
            [=](double f) {
                std::string text;
                {
                    std::lock_guard lk(phase->m);
                    if (f < 1.0 && secondsSince(phase->last) < kProgressInterval) return;
                    phase->last = Clock::now();
                    text = message(phase->name, f);
                }
                send(text);
            }};
}

std::string randomToken() {
    std::random_device rd;  // /dev/urandom on Linux
    static const char* hex = "0123456789abcdef";
    std::string t;
    for (int i = 0; i < 32; ++i) t += hex[rd() & 15];
    return t;
}

/// Equal strings, in time independent of where they differ.
bool sameSecret(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    unsigned char diff = 0;
    for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
    return diff == 0;
}

/// The value of `key` in a target's query string ("/ws?token=abc&x=1"), if present.
std::optional<std::string> queryValue(std::string_view target, std::string_view key) {
    const auto q = target.find('?');
    if (q == std::string_view::npos) return std::nullopt;
    std::string_view rest = target.substr(q + 1);
    while (!rest.empty()) {
        const auto amp = rest.find('&');
        const std::string_view pair = rest.substr(0, amp);
        const auto eq = pair.find('=');
        if (pair.substr(0, eq) == key)
            return std::string(eq == std::string_view::npos ? "" : pair.substr(eq + 1));
        if (amp == std::string_view::npos) break;
        rest = rest.substr(amp + 1);
    }
    return std::nullopt;
}

/// The value of cookie `name` in a Cookie header, if present.
std::optional<std::string> cookieValue(std::string_view header, std::string_view name) {
    while (!header.empty()) {
        const auto semi = header.find(';');
        std::string_view pair = header.substr(0, semi);
        while (!pair.empty() && pair.front() == ' ') pair.remove_prefix(1);
        const auto eq = pair.find('=');
        if (eq != std::string_view::npos && pair.substr(0, eq) == name)
            return std::string(pair.substr(eq + 1));
        if (semi == std::string_view::npos) break;
        header = header.substr(semi + 1);
    }
    return std::nullopt;
}

std::string_view pathOf(std::string_view target) {
    return target.substr(0, target.find('?'));
}

/// "uvr render" arguments quoted for a POSIX shell where needed.
std::string shellQuote(const std::string& arg) {
    const bool plain = !arg.empty() && std::all_of(arg.begin(), arg.end(), [](unsigned char c) {
        return std::isalnum(c) || std::string_view("_-./:,=+@%").find(c) != std::string_view::npos;
    });
    if (plain) return arg;
    std::string out = "'";
    for (char c : arg) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

/// The shortest decimal that reads back as the same float.
std::string fmtExact(float v) {
    char buf[40];
    for (int digits = 6; digits <= 9; ++digits) {
        std::snprintf(buf, sizeof buf, "%.*g", digits, double(v));
        if (std::strtof(buf, nullptr) == v) break;
    }
    return buf;
}

/// ParaView's "set view direction" buttons: the view direction and view up of each axis.
std::optional<std::pair<Vec3f, Vec3f>> axisView(const std::string& axis) {
    const Vec3f z(0.f, 0.f, 1.f), y(0.f, 1.f, 0.f);
    if (axis == "+x") return std::make_pair(Vec3f(1.f, 0.f, 0.f), z);
    if (axis == "-x") return std::make_pair(Vec3f(-1.f, 0.f, 0.f), z);
    if (axis == "+y") return std::make_pair(Vec3f(0.f, 1.f, 0.f), z);
    if (axis == "-y") return std::make_pair(Vec3f(0.f, -1.f, 0.f), z);
    if (axis == "+z") return std::make_pair(Vec3f(0.f, 0.f, 1.f), y);
    if (axis == "-z") return std::make_pair(Vec3f(0.f, 0.f, -1.f), y);
    return std::nullopt;
}

Json histogramOf(const std::vector<float>& values, std::pair<float, float> range) {
    std::vector<std::uint64_t> counts(kHistogramBins, 0);
    const double lo = range.first, hi = range.second;
    const double scale = hi > lo ? kHistogramBins / (hi - lo) : 0.0;
    for (float v : values) {
        if (!std::isfinite(v)) continue;
        const int bin = std::clamp(static_cast<int>((v - lo) * scale), 0, kHistogramBins - 1);
        ++counts[bin];
    }
    return {{"range", {range.first, range.second}}, {"counts", counts}};
}

/// What the server knows of a field once a tab has shown it: its finite range and histogram.
struct FieldEntry {
    std::pair<float, float> range{0.f, 1.f};
    Json histogram;
};

class Session;
class HttpConnection;

}  // namespace

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
};

namespace {

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

    void start(http::request<http::string_body> req) {
        ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
        ws_.read_message_max(server_.opt.maxMessageBytes);
        ws_.async_accept(req,
                         [self = shared_from_this()](beast::error_code ec) { self->onAccept(ec); });
    }

    /// Queues a text message (network thread). With `supersedes` (its type: "state", "export",
    /// "histogram", "progress"), it replaces a message of that type still waiting: a tab that
    /// reads slowly gets the newest of each, not every one.
    void sendText(std::string text, std::string_view supersedes = {}) {
        queue(false, std::move(text), false, supersedes);
    }
    /// Queues a frame's description and image; the frame ends when its image is written
    /// (network thread).
    void sendImage(std::string meta, std::string bytes) {
        queue(false, std::move(meta), false);
        queue(true, std::move(bytes), true);
    }
    /// Ends the connection at once (the server shuts down; network thread): the page sees the
    /// socket close and says the connection was lost.
    void shutdown() {
        closed_ = true;
        beast::error_code ignored;
        auto& socket = beast::get_lowest_layer(ws_).socket();
        socket.shutdown(tcp::socket::shutdown_both, ignored);
        socket.close(ignored);
    }

    /// Queues an `error` answering `request`, its message cut to kMaxErrorBytes.
    void sendError(const std::string& message, const std::string& request) {
        sendText(Json{{"type", "error"},
                      {"message", printableShort(message, kMaxErrorBytes)},
                      {"request", request}}
                     .dump(-1, ' ', false, Json::error_handler_t::replace));
    }

private:
    struct Out {
        bool binary;
        std::string data;
        bool endsFrame;
        std::string_view kind;  ///< the type a newer message replaces it for, or empty
    };

    void onAccept(beast::error_code ec) {
        if (ec) return;
        Json info;
        {
            std::lock_guard lk(server_.m);
            if (static_cast<int>(liveSessionsLocked()) >= server_.opt.maxSessions) {
                // Checked again here: several upgrades may have raced past the HTTP check.
                ws_.async_close(websocket::close_reason(websocket::close_code::try_again_later),
                                [self = shared_from_this()](beast::error_code) {});
                return;
            }
            state = server_.scene.initial;
            histogramKey = server_.fieldKey(state.field, state.step);  // info carries its histogram
            server_.sessions.push_back(weak_from_this());
            info = server_.infoBase;
            info["state"] = toJson(state);
        }
        peer = endpointName();
        server_.say("view: " + peer + " connected");
        {
            std::lock_guard lk(server_.fieldsMutex);
            const auto it = server_.fields.find(server_.fieldKey(state.field, state.step));
            if (it != server_.fields.end()) {
                info["histogram"] = it->second.histogram;
                info["histogram"]["field"] = state.field;
            }
        }
        sendText(info.dump(-1, ' ', false, Json::error_handler_t::replace));
        server_.cv.notify_all();
        doRead();
    }

    std::size_t liveSessionsLocked() {
        auto& v = server_.sessions;
        v.erase(std::remove_if(v.begin(), v.end(), [](const auto& w) { return w.expired(); }),
                v.end());
        return v.size();
    }

    std::string endpointName() {
        beast::error_code ec;
        const auto ep = beast::get_lowest_layer(ws_).socket().remote_endpoint(ec);
        return ec ? "a client" : ep.address().to_string() + ":" + std::to_string(ep.port());
    }

    void doRead() {
        ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
            self->onRead(ec);
        });
    }

    void onRead(beast::error_code ec) {
        if (ec) {
            if (ec == websocket::error::message_too_big)
                server_.say("view: " + peer + " sent a message over " +
                            std::to_string(server_.opt.maxMessageBytes) +
                            " bytes: connection closed");
            else if (ec != websocket::error::closed && ec != net::error::operation_aborted &&
                     ec != net::error::eof)
                server_.say("view: " + peer + " disconnected (" + ec.message() + ")");
            else
                server_.say("view: " + peer + " disconnected");
            closed_ = true;
            return;  // the last reference goes with the pending operations
        }
        const bool binary = ws_.got_binary();
        std::string text = beast::buffers_to_string(buffer_.data());
        buffer_.consume(buffer_.size());
        if (admit()) {
            if (binary)
                sendError("binary messages are not accepted: send JSON text", "");
            else
                handle(text);
        }
        doRead();
    }

    /// Token bucket of maxMessagesPerSecond: false (and one error a second) when over.
    bool admit() {
        const auto now = Clock::now();
        const double rate = server_.opt.maxMessagesPerSecond;
        tokens_ = std::min(
            rate, tokens_ + rate * std::chrono::duration<double>(now - lastRefill_).count());
        lastRefill_ = now;
        if (tokens_ >= 1.0) {
            tokens_ -= 1.0;
            return true;
        }
        ++dropped_;
        if (now - lastDropReport_ >= std::chrono::seconds(1)) {
            lastDropReport_ = now;
            sendError("too many messages: " + std::to_string(dropped_) + " dropped (at most " +
                          std::to_string(server_.opt.maxMessagesPerSecond) + " a second)",
                      "");
        }
        return false;
    }

    void handle(const std::string& text) {
        Json msg;
        std::string type;
        try {
            // Nesting is bounded before parsing: nothing below (a copy, a description in an
            // error) then recurses deeper than kMaxJsonDepth.
            if (const std::size_t at = jsonTooDeepAt(text); at != std::string_view::npos)
                throwError(ErrorKind::Argument, "",
                           "JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                               " levels (at byte " + std::to_string(at) + ")");
            msg = Json::parse(text);
            if (!msg.is_object() || !msg.contains("type") || !msg["type"].is_string())
                throwError(ErrorKind::Argument, "",
                           "expected a JSON object with a \"type\" string");
            type = msg["type"].get<std::string>();
            if (type == "set")
                onSet(msg);
            else if (type == "reset_camera")
                onResetCamera(msg);
            else if (type == "snapshot")
                onSnapshot();
            else if (type == "export")
                onExport();
            else if (type == "ping")
                onPing(msg);
            else
                throwError(ErrorKind::Argument, "",
                           "unknown message type \"" + printableShort(type, 40) +
                               "\" (set, reset_camera, snapshot, export, ping)");
        } catch (const Json::exception& e) {
            refused(std::string("malformed JSON: ") + e.what(), type, msg);
        } catch (const Error& e) {
            refused(e.what(), type, msg);
        } catch (const std::exception& e) {
            refused(std::string("failed: ") + e.what(), type, msg);
        }
    }

    /// Answers a refused request: the error (with the request's seq, when it had one) and, for a
    /// state change, the state as it stays, so that the page can show it again.
    void refused(const std::string& message, const std::string& type, const Json& msg) {
        Json e = {{"type", "error"},
                  {"message", printableShort(message, kMaxErrorBytes)},
                  {"request", printableShort(type, 40)}};
        if (msg.is_object())
            if (auto it = msg.find("seq"); it != msg.end() && it->is_number_unsigned())
                e["seq"] = *it;
        sendText(e.dump(-1, ' ', false, Json::error_handler_t::replace));
        if (type == "set" || type == "reset_camera") sendState();
    }

    /// Checks the keys every state change may carry (seq, interactive) before anything changes.
    static void checkChangeKeys(const Json& msg) {
        if (auto it = msg.find("seq"); it != msg.end() && !it->is_number_unsigned())
            throwError(ErrorKind::Argument, "", "\"seq\": expected a non-negative integer");
        if (auto it = msg.find("interactive"); it != msg.end() && !it->is_boolean())
            throwError(ErrorKind::Argument, "", "\"interactive\": expected true or false");
    }

    /// Records a change of the state (under Impl::m; checkChangeKeys passed).
    void markChanged(const Json& msg) {
        if (auto it = msg.find("seq"); it != msg.end()) seq = it->get<std::uint64_t>();
        demand.changed(msg.value("interactive", false), Clock::now());
    }

    void onSet(const Json& msg) {
        checkChangeKeys(msg);
        SetResult r;
        {
            std::lock_guard lk(server_.m);
            ViewState next = state;
            r = applySet(next, msg, server_.stepCount());
            if (r.fieldChanged) server_.fieldKey(next.field);  // names a field of the mesh?
            state = std::move(next);
            if (r.fieldChanged) resetRange = !r.rangeGiven;
            markChanged(msg);
        }
        server_.cv.notify_all();
        if (r.echoState) sendState();
    }

    void onResetCamera(const Json& msg) {
        checkChangeKeys(msg);
        std::string axis;
        if (auto it = msg.find("axis"); it != msg.end() && !it->is_null()) {
            if (!it->is_string() || !axisView(it->get<std::string>()))
                throwError(ErrorKind::Argument, "",
                           "\"axis\": expected \"+x\", \"-x\", \"+y\", \"-y\", \"+z\" or \"-z\"");
            axis = it->get<std::string>();
        }
        {
            std::lock_guard lk(server_.m);
            Camera cam =
                resetCamera(server_.scene.bounds, float(state.width) / float(state.height));
            if (const auto view = axisView(axis)) {
                const Vec3f offset = cam.position - cam.focalPoint;
                const float distance = std::sqrt(dot(offset, offset));
                cam.position = cam.focalPoint - view->first * distance;
                cam.viewUp = view->second;
            }
            cam.parallelProjection = state.camera.parallelProjection;
            state.camera = cam;
            markChanged(msg);
        }
        server_.cv.notify_all();
        sendState();
    }

    void onPing(const Json& msg) {
        Json seqValue;
        if (auto it = msg.find("seq"); it != msg.end()) {
            if (!it->is_number_unsigned())
                throwError(ErrorKind::Argument, "", "\"seq\": expected a non-negative integer");
            seqValue = *it;
        }
        sendText(Json{{"type", "pong"}, {"seq", seqValue}}.dump());
    }

    void onSnapshot() {
        {
            std::lock_guard lk(server_.m);
            demand.snapshot = true;
        }
        server_.cv.notify_all();
    }

    void onExport() {
        ViewState s;
        {
            std::lock_guard lk(server_.m);
            s = state;
        }
        sendText(server_.exportMessage(s).dump(-1, ' ', false, Json::error_handler_t::replace),
                 "export");
    }

    void sendState() {
        Json j;
        {
            std::lock_guard lk(server_.m);
            j = {{"type", "state"}, {"state", toJson(state)}};
        }
        sendText(j.dump(-1, ' ', false, Json::error_handler_t::replace), "state");
    }

    /// Queues a message: at most kMaxOutbox messages and opt.maxQueuedBytes of text wait (a
    /// tab has at most one frame's image queued: the render thread waits for it to be sent);
    /// past either the connection counts as not reading and is closed. The first message of
    /// an empty queue always goes.
    void queue(bool binary, std::string data, bool endsFrame, std::string_view kind = {}) {
        if (closed_) {
            if (endsFrame) frameDone();
            return;
        }
        if (!kind.empty()) {
            // The message being written (the front, while writing_) stays.
            auto it = outbox_.begin();
            if (writing_ && it != outbox_.end()) ++it;
            for (; it != outbox_.end(); ++it)
                if (it->kind == kind) {
                    queuedTextBytes_ -= it->binary ? 0 : it->data.size();
                    outbox_.erase(it);
                    break;
                }
        }
        const std::size_t textBytes = binary ? 0 : data.size();
        if (!outbox_.empty() && (outbox_.size() >= kMaxOutbox ||
                                 queuedTextBytes_ + textBytes > server_.opt.maxQueuedBytes)) {
            server_.say("view: " + peer + " does not read its messages (" +
                        std::to_string(outbox_.size()) + " waiting, " +
                        std::to_string(queuedTextBytes_ + textBytes) +
                        " bytes of text): connection closed");
            closed_ = true;
            beast::error_code ignored;
            beast::get_lowest_layer(ws_).socket().close(ignored);
            if (endsFrame) frameDone();
            return;
        }
        queuedTextBytes_ += textBytes;
        outbox_.push_back({binary, std::move(data), endsFrame, kind});
        pump();
    }

    void pump() {
        if (writing_ || outbox_.empty()) return;
        writing_ = true;
        // A write that waits too long means the tab does not read: close it (a read failing
        // meanwhile, e.g. on a message too big, waits for this write to send its close frame).
        writeTimer_.expires_after(seconds(server_.opt.stalledWriteSeconds));
        writeTimer_.async_wait([self = shared_from_this()](beast::error_code ec) {
            if (ec || self->closed_ || !self->writing_) return;
            self->server_.say("view: " + self->peer + " does not read its messages (a write " +
                              "waited " + fmtSeconds(self->server_.opt.stalledWriteSeconds) +
                              " s): connection closed");
            self->closed_ = true;
            beast::error_code ignored;
            beast::get_lowest_layer(self->ws_).socket().close(ignored);
        });
        ws_.binary(outbox_.front().binary);
        ws_.async_write(
            net::buffer(outbox_.front().data),
            [self = shared_from_this()](beast::error_code ec, std::size_t) { self->onWrite(ec); });
    }

    void onWrite(beast::error_code ec) {
        writing_ = false;
        writeTimer_.cancel();
        const bool endsFrame = outbox_.front().endsFrame;
        if (!outbox_.front().binary) queuedTextBytes_ -= outbox_.front().data.size();
        outbox_.pop_front();
        if (endsFrame) frameDone();
        if (ec) {
            closed_ = true;
            for (const Out& o : outbox_)
                if (o.endsFrame) frameDone();
            outbox_.clear();
            queuedTextBytes_ = 0;
            return;
        }
        pump();
    }

    void frameDone() {
        {
            std::lock_guard lk(server_.m);
            demand.finished();
        }
        server_.cv.notify_all();
    }

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

/// One HTTP connection: serves the page and its files, or hands a WebSocket upgrade to a
/// Session.
class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
public:
    HttpConnection(ViewServer::Impl& server, tcp::socket&& socket)
        : server_(server), stream_(std::move(socket)) {}

    void start() { doRead(); }

    /// Ends the connection (to make room for a new one; network thread).
    void close() {
        beast::error_code ignored;
        stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
        stream_.close();
    }

private:
    void doRead() {
        parser_.emplace();
        parser_->header_limit(16 * 1024);
        parser_->body_limit(64 * 1024);
        stream_.expires_after(seconds(server_.opt.idleSeconds));
        http::async_read(
            stream_, buffer_, *parser_,
            [self = shared_from_this()](beast::error_code ec, std::size_t) { self->onRead(ec); });
    }

    bool tokenIn(const http::request<http::string_body>& req, bool allowCookie) const {
        const std::string& token = server_.opt.token;
        if (auto q = queryValue(req.target(), "token"); q && sameSecret(*q, token)) return true;
        if (!allowCookie) return false;
        const auto it = req.find(http::field::cookie);
        if (it == req.end()) return false;
        const auto c = cookieValue(it->value(), cookieName());
        return c && sameSecret(*c, token);
    }

    std::string cookieName() const { return "uvr_token_" + std::to_string(server_.boundPort); }

    void onRead(beast::error_code ec) {
        if (ec) return;  // closed, timed out or malformed: drop the connection
        http::request<http::string_body> req = parser_->release();
        const std::string_view path = pathOf(req.target());
        if (websocket::is_upgrade(req)) {
            // The socket needs the token in its URL: a cookie alone would let another site's
            // page open one.
            if (path != "/ws") return respond(req, http::status::not_found, "no such socket\n");
            if (!tokenIn(req, false))
                return respond(req, http::status::forbidden,
                               "uvr view: missing or wrong token in the socket URL\n");
            {
                std::lock_guard lk(server_.m);
                auto& v = server_.sessions;
                v.erase(
                    std::remove_if(v.begin(), v.end(), [](const auto& w) { return w.expired(); }),
                    v.end());
                if (static_cast<int>(v.size()) >= server_.opt.maxSessions)
                    return respond(req, http::status::service_unavailable,
                                   "uvr view: too many connections\n");
            }
            stream_.expires_never();
            std::make_shared<Session>(server_, stream_.release_socket())->start(std::move(req));
            return;
        }
        if (req.method() != http::verb::get)
            return respond(req, http::status::method_not_allowed, "GET only\n");
        if (!tokenIn(req, path != "/"))
            return respond(req, http::status::forbidden,
                           "uvr view: missing or wrong token: open the URL that uvr view printed "
                           "(with ?token=...)\n");
        const std::string name = path == "/" ? "index.html" : std::string(path.substr(1));
        const WebAsset* asset = findWebAsset(name);
        if (!asset) return respond(req, http::status::not_found, "not found\n");
        http::response<http::string_body> res{http::status::ok, req.version()};
        res.set(http::field::content_type, asset->mime);
        res.set(http::field::cache_control, "no-store");
        res.set("X-Content-Type-Options", "nosniff");
        res.set("Referrer-Policy", "no-referrer");
        res.set("Content-Security-Policy",
                "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'; "
                "style-src 'self'; script-src 'self'; frame-ancestors 'none'");
        if (path == "/")
            res.set(http::field::set_cookie,
                    cookieName() + "=" + server_.opt.token + "; Path=/; HttpOnly; SameSite=Strict");
        res.body() = std::string(asset->content);
        res.prepare_payload();
        res.keep_alive(req.keep_alive());
        write(std::move(res));
    }

    void respond(const http::request<http::string_body>& req, http::status status,
                 std::string body) {
        http::response<http::string_body> res{status, req.version()};
        res.set(http::field::content_type, "text/plain; charset=utf-8");
        res.set(http::field::cache_control, "no-store");
        res.body() = std::move(body);
        res.prepare_payload();
        res.keep_alive(req.keep_alive());
        write(std::move(res));
    }

    void write(http::response<http::string_body>&& res) {
        auto sp = std::make_shared<http::response<http::string_body>>(std::move(res));
        http::async_write(
            stream_, *sp, [self = shared_from_this(), sp](beast::error_code ec, std::size_t) {
                if (ec) return;
                if (!sp->keep_alive()) {
                    beast::error_code ignored;
                    self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                    return;
                }
                self->doRead();
            });
    }

    ViewServer::Impl& server_;
    beast::tcp_stream stream_;
    beast::flat_buffer buffer_;
    std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace

FieldEntry ViewServer::Impl::field(const std::string& spec, std::size_t step,
                                   const ProgressFn& progress) {
    const std::string key = fieldKey(spec, step);
    if (renderer && key == rendererKey) {
        std::lock_guard lk(fieldsMutex);
        return fields.at(key);
    }
    if (step != meshStep) {
        // Another time step: its fields for the same points and cells, nothing geometric.
        const auto start = Clock::now();
        std::optional<std::vector<Field>> stepFields =
            scene.series->readFieldsIfSameGeometry(step, *scene.mesh);
        if (!stepFields)
            throwError(ErrorKind::Unsupported, scene.series->stepSource(step),
                       "time step " + std::to_string(step) +
                           " has other points or cells than "
                           "step " +
                           std::to_string(meshStep) +
                           ": the viewer shows the time steps of one geometry (uvr animate renders "
                           "any)");
        std::vector<FieldInfo> infos;
        for (const Field& f : *stepFields) infos.push_back({f.name, f.association, f.components});
        if (resolveField(infos, parseFieldSpec(spec)).index !=
            resolveField(fieldInfos, parseFieldSpec(spec)).index)
            throwError(ErrorKind::Unsupported, scene.series->stepSource(step),
                       "time step " + std::to_string(step) +
                           " lists its fields otherwise than "
                           "step " +
                           std::to_string(meshStep) + ": the viewer needs the same fields");
        scene.mesh->fields = std::move(*stepFields);
        meshStep = step;
        char line[160];
        std::snprintf(line, sizeof line, "view: read time step %zu (time %.9g) in %.3f s", step,
                      scene.series->times()[step], secondsSince(start));
        say(line);
    }
    const ScalarField values = selectScalarField(*scene.mesh, parseFieldSpec(spec));
    FieldEntry entry;
    entry.range = finiteRange(values.values);
    entry.histogram = histogramOf(values.values, entry.range);
    const auto start = Clock::now();
    char line[200];
    if (!renderer) {
        say("view: preparing " + values.describe());
        renderer = std::make_unique<Renderer>(*scene.mesh, values, scene.rendererOptions, progress);
        std::snprintf(line, sizeof line, "view: prepared %s in %.2f s", values.describe().c_str(),
                      secondsSince(start));
    } else {
        // The same mesh: only the values and what depends on them change. Until that is done
        // the renderer holds no field known by key (a failure leaves it to be set again).
        rendererKey.clear();
        renderer->setFieldValues(values);
        std::snprintf(line, sizeof line, "view: switched to %s in %.3f s (no geometry rebuilt)",
                      values.describe().c_str(), secondsSince(start));
    }
    rendererKey = key;
    say(line);
    std::lock_guard lk(fieldsMutex);
    return fields[key] = std::move(entry);
}

/// The vocabulary's entries of the settings the page sets (kViewerSettings): their choices,
/// ranges and docs for its controls.
static Json viewerVocabulary() {
    Json out = Json::array();
    for (const Json& d : settingsVocabularyJson())
        if (isViewerSetting(d["name"].get<std::string>())) out.push_back(d);
    return out;
}

Json ViewServer::Impl::exportMessage(const ViewState& state) const {
    ViewState s = state;
    // A log scale over a range from 0 or below maps as the frames do (ParaView's
    // AdjustRangeForLog, makeFrameSetup): export the range they use.
    if (s.tf.logScale && !(s.range.first > 0.f) && s.range.second > 0.f)
        s.range.first = std::fmin(s.range.second * 1e-4f, 1.f);
    std::vector<std::string> args = {"uvr", "render", scene.file};
    if (stepCount() > 1) args.insert(args.end(), {"--step-index", std::to_string(s.step)});
    if (!s.field.empty()) args.insert(args.end(), {"--field", s.field});
    // The state's settings as the frames use them (the command line's where the page set none).
    const RenderSettings f = frameSettings(s, scene.base);
    args.insert(args.end(), {"--tf", "uvr-tf.json", "--camera", "uvr-camera.pvcc", "--range",
                             fmtExact(s.range.first) + "," + fmtExact(s.range.second), "--size",
                             std::to_string(s.width) + "x" + std::to_string(s.height)});
    // The page's settings by their flags: the method always, the others where they are not the
    // default (the opacity unit always is: the server sets it to ParaView's), and what tunes the
    // adaptive method when it renders.
    for (const char* name : kViewerSettings) {
        const SettingDef& def = settingNamed(name);
        const Json value = def.get(f);
        if (std::string_view(def.name) != "method" && value == settingDefault(def) &&
            !(def.tunesAdaptive && f.method == RenderMethod::Partitions))
            continue;
        args.push_back(cliFlag(def));
        args.push_back(value.is_string() ? value.get<std::string>() : fmtExact(value.get<float>()));
    }
    args.insert(args.end(), scene.commandFlags.begin(), scene.commandFlags.end());
    args.insert(args.end(), {"-o", "uvr-view.png"});
    std::string command;
    for (const std::string& a : args) command += (command.empty() ? "" : " ") + shellQuote(a);
    return {{"type", "export"},
            {"tf_json", paraViewColorMapJson(s.tf, s.range.first, s.range.second)},
            {"pvcc", pvccText(s.camera)},
            {"tf_file", "uvr-tf.json"},
            {"camera_file", "uvr-camera.pvcc"},
            {"command", command}};
}

void ViewServer::Impl::broadcast(const std::string& text, std::string_view supersedes) {
    net::post(ioc, [this, text, supersedes] {
        std::vector<std::shared_ptr<Session>> live;
        {
            std::lock_guard lk(m);
            for (const auto& w : sessions)
                if (auto s = w.lock()) live.push_back(std::move(s));
        }
        for (const auto& s : live) s->sendText(text, supersedes);
    });
}

void ViewServer::Impl::prepareAtStart() {
    if (renderer) return;
    const auto start = Clock::now();
    try {
        field(scene.initial.field, scene.initial.step,
              progressMessages([this](const std::string& text) { broadcast(text, "progress"); },
                               [this](const std::string& phase) { say("view: " + phase); }));
    } catch (const std::exception& e) {
        // Said to the log and the page; the first frame tries again and answers with the error.
        say(std::string("view: preparation failed: ") + e.what());
        broadcast(Json{{"type", "error"},
                       {"message", printableShort(e.what(), kMaxErrorBytes)},
                       {"request", "prepare"}}
                      .dump(-1, ' ', false, Json::error_handler_t::replace));
        return;
    }
    Json prepared = {{"type", "prepared"},
                     {"tetrahedra", renderer->prepared().tets.tetCount()},
                     {"rendered_cells", describeCells(renderer->prepared().tets)},
                     {"prepare_seconds", secondsSince(start)},
                     {"device", renderer->deviceDescription()}};
    {
        std::lock_guard lk(m);
        for (const char* key : {"tetrahedra", "rendered_cells", "prepare_seconds", "device"})
            infoBase[key] = prepared[key];
    }
    broadcast(prepared.dump());
}

void ViewServer::Impl::renderLoop() {
    prepareAtStart();
    const ScheduleOptions schedule{std::chrono::milliseconds(opt.refineDelayMs), opt.targetFrameMs,
                                   opt.maxScale};
    const FrameEncoding encoding{scene.background, opt.jpegQuality};
    std::unique_lock lk(m);
    while (!stopping) {
        // Step 1: the next tab with work (frame_scheduler.h), or wait for one.
        std::vector<std::shared_ptr<Session>> live(sessions.size());
        std::vector<const FrameDemand*> demands(sessions.size());
        for (std::size_t i = 0; i < sessions.size(); ++i)
            if ((live[i] = sessions[i].lock())) demands[i] = &live[i]->demand;
        const FramePick pick = pickFrame(demands, roundRobin, Clock::now(), schedule);
        // The last reference to a closed connection goes on the network thread, which owns its
        // socket.
        const auto release = [this](std::vector<std::shared_ptr<Session>>& refs) {
            net::post(ioc, [refs = std::move(refs)] {});
            refs.clear();
        };
        if (!pick.tab) {
            release(live);
            if (pick.wakeAt == Clock::time_point::max())
                cv.wait(lk);
            else
                cv.wait_until(lk, pick.wakeAt);
            continue;
        }
        roundRobin = *pick.tab + 1;
        std::shared_ptr<Session> s = live[*pick.tab];
        release(live);
        // Step 2: take the state; newer changes wait for this frame to be sent.
        const FrameKind kind = pick.kind;
        ViewState state = s->state;
        const std::uint64_t seq = s->seq;
        const int scale =
            kind == FrameKind::Reduced
                ? reducedScale(s->demand.msPerPixel, double(state.width) * state.height, schedule)
                : 1;
        s->demand.start(kind);
        const bool resetRange = s->resetRange;
        const std::string histogramKey = s->histogramKey;
        s->resetRange = false;
        lk.unlock();

        // Step 3: the field (prepared or swapped in), then the frame, outside the lock.
        std::weak_ptr<Session> weak = s;
        auto post = [&](std::function<void(Session&)> f) {
            net::post(ioc, [weak, f = std::move(f)] {
                if (auto c = weak.lock()) f(*c);
            });
        };
        bool sent = false;
        try {
            const std::string key = fieldKey(state.field, state.step);
            const FieldEntry entry =
                field(state.field, state.step, progressMessages([&](const std::string& text) {
                          post([text](Session& c) { c.sendText(text, "progress"); });
                      }));
            if (resetRange) {
                state.range = entry.range;
                if (!(state.range.first < state.range.second))
                    state.range.second = state.range.first + 1.f;
                std::lock_guard slk(m);
                s->state.range = state.range;
            }
            if (key != histogramKey || resetRange) {
                {
                    std::lock_guard slk(m);
                    s->histogramKey = key;
                }
                Json h = entry.histogram;
                h["type"] = "histogram";
                h["field"] = state.field;
                Json st = {{"type", "state"}, {"state", toJson(state)}};
                post([h = h.dump(), st = st.dump()](Session& c) {
                    c.sendText(h, "histogram");
                    c.sendText(st, "state");
                });
            }
            ViewFrame frame =
                renderViewFrame(*renderer, state, scene.base, kind, scale, seq, encoding);
            {
                std::lock_guard slk(m);
                s->demand.measured(frame.msPerPixel);
            }
            post([meta = frame.meta.dump(), bytes = std::move(frame.bytes)](Session& c) mutable {
                c.sendImage(meta, std::string(bytes.begin(), bytes.end()));
            });
            sent = true;
        } catch (const std::exception& e) {
            // A step or field that fails to read (uvr::Error, bad_alloc, anything): this tab
            // hears why, the server goes on serving it and the others.
            const std::string message = printableShort(e.what(), kMaxErrorBytes);
            say("view: frame failed: " + message);
            post([message](Session& c) { c.sendError(message, "frame"); });
        } catch (...) {
            say("view: frame failed: unknown exception");
            post([](Session& c) { c.sendError("failed (unknown exception)", "frame"); });
        }
        lk.lock();
        if (!sent) s->demand.finished();
        // The last reference to a closed connection goes on the network thread, which owns
        // its socket.
        net::post(ioc, [s = std::move(s)] {});
    }
}

void ViewServer::Impl::acceptLoop() {
    if (!acceptor.is_open()) return;
    acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code ec, tcp::socket socket) {
        if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
        if (ec) return acceptFailed(ec);
        acceptDelay = std::chrono::milliseconds(0);
        admitConnection(std::move(socket));
        acceptLoop();
    });
}

void ViewServer::Impl::acceptFailed(const beast::error_code& ec) {
    // Retrying at once would spin: a descriptor frees only when a connection ends.
    ++acceptFailures;
    acceptDelay =
        acceptDelay.count() == 0 ? kAcceptRetryFirst : std::min(acceptDelay * 2, kAcceptRetryMax);
    const bool noDescriptor = ec.value() == EMFILE || ec.value() == ENFILE;
    const bool freed = noDescriptor && closeOldestHttp();
    const auto now = Clock::now();
    if (now - lastAcceptLog >= kAcceptLogInterval) {
        lastAcceptLog = now;
        say("view: accept failed (" + ec.message() + "; " + std::to_string(acceptFailures) +
            " failure(s) so far): " + (freed ? "closed the oldest page connection, " : "") +
            "retrying in " + std::to_string(acceptDelay.count()) + " ms");
    }
    acceptRetry.expires_after(acceptDelay);
    acceptRetry.async_wait([this](beast::error_code wait) {
        if (!wait) acceptLoop();
    });
}

bool ViewServer::Impl::closeOldestHttp() {
    while (!httpConnections.empty()) {
        auto c = httpConnections.front().lock();
        httpConnections.pop_front();
        if (c) {
            c->close();
            return true;
        }
    }
    return false;
}

void ViewServer::Impl::admitConnection(tcp::socket socket) {
    httpConnections.erase(std::remove_if(httpConnections.begin(), httpConnections.end(),
                                         [](const auto& w) { return w.expired(); }),
                          httpConnections.end());
    std::size_t sessionCount = 0;
    {
        std::lock_guard lk(m);
        for (const auto& w : sessions) sessionCount += !w.expired();
    }
    if (httpConnections.size() + sessionCount >= static_cast<std::size_t>(connectionCap) &&
        !closeOldestHttp()) {
        beast::error_code ignored;
        socket.close(ignored);  // every place is a WebSocket: the newcomer waits its turn
        return;
    }
    // Frames go out as two messages (description, image): no Nagle delay between them.
    beast::error_code ignored;
    socket.set_option(tcp::no_delay(true), ignored);
    auto c = std::make_shared<HttpConnection>(*this, std::move(socket));
    httpConnections.push_back(c);
    c->start();
}

void ViewServer::Impl::requestStop() {
    {
        std::lock_guard lk(m);
        if (stopping) return;
        stopping = true;
    }
    cv.notify_all();
}

namespace {

/// The address of the options' host ("localhost" is 127.0.0.1); Error(Argument) when it is not
/// an IP address.
net::ip::address hostAddress(const ServerOptions& o) {
    if (o.host == "localhost") return net::ip::address_v4::loopback();
    beast::error_code ec;
    const auto address = net::ip::make_address(o.host, ec);
    if (ec)
        throwError(
            ErrorKind::Argument, "",
            "`host` " + printableShort(o.host, 60) + ": not an IP address (" + ec.message() + ")");
    return address;
}

/// Opens, binds and (with `listen`) listens on the options' address; Error(Io) naming it.
void bindTo(tcp::acceptor& acceptor, const ServerOptions& o, bool listen) {
    const tcp::endpoint endpoint(hostAddress(o), o.port);
    beast::error_code ec;
    acceptor.open(endpoint.protocol(), ec);
    if (!ec) acceptor.set_option(net::socket_base::reuse_address(true), ec);
    if (!ec) acceptor.bind(endpoint, ec);
    if (!ec && listen) acceptor.listen(net::socket_base::max_listen_connections, ec);
    if (ec)
        throwError(
            ErrorKind::Io, "",
            "cannot listen on " + o.host + ":" + std::to_string(o.port) + ": " + ec.message());
}

}  // namespace

void checkServerOptions(const ServerOptions& o, bool tryAddress) {
    if (!o.token.empty()) {
        const bool ok = o.token.size() >= kMinTokenLength &&
                        std::all_of(o.token.begin(), o.token.end(), [](unsigned char c) {
                            return std::isalnum(c) || c == '_' || c == '-';
                        });
        if (!ok)
            throwError(ErrorKind::Argument, "",
                       "`token`: expected " + std::to_string(kMinTokenLength) +
                           " or more characters from A-Z, a-z, 0-9, _ and -");
    }
    if (o.maxSessions < 1 || o.maxMessagesPerSecond < 1 || o.maxScale < 1 || o.maxConnections < 1 ||
        o.maxMessageBytes < 1 || o.maxQueuedBytes < 1 || !(o.idleSeconds > 0.0) ||
        !(o.stalledWriteSeconds > 0.0))
        throwError(ErrorKind::Argument, "", "server limits must be positive");
    hostAddress(o);
    if (tryAddress) {
        net::io_context ioc;
        tcp::acceptor probe(ioc);
        bindTo(probe, o, false);
    }
}

ViewServer::ViewServer(ViewScene scene, ServerOptions options, LogFn log)
    : impl_(std::make_unique<Impl>()) {
    Impl& d = *impl_;
    if (!scene.mesh) throwError(ErrorKind::Argument, "", "the viewer needs a mesh");
    checkServerOptions(options, false);
    if (options.token.empty()) options.token = randomToken();
    d.scene = std::move(scene);
    d.opt = std::move(options);
    d.log = std::move(log);
    const Mesh& mesh = *d.scene.mesh;
    // The fields as the page lists them, with their ranges.
    Json fields = Json::array();
    const std::optional<std::size_t> def = defaultFieldIndex(mesh);
    for (std::size_t i = 0; i < mesh.fields.size(); ++i) {
        const Field& f = mesh.fields[i];
        d.fieldInfos.push_back({f.name, f.association, f.components});
        const auto range = finiteRange(scalarFieldOf(mesh, f).values);
        fields.push_back({{"name", f.name},
                          {"association", associationName(f.association)},
                          {"components", f.components},
                          {"range", {range.first, range.second}},
                          {"default", def == i}});
    }
    d.fieldKey(d.scene.initial.field);  // the starting field exists
    std::map<std::string, std::uint64_t> types;
    for (CellType t : mesh.cellTypes) ++types[cellTypeName(t)];
    const Bounds3f& b = d.scene.bounds;
    std::vector<std::string> presets;
    for (const ColorMapInfo& p : transferFunctionPresets()) presets.push_back(p.name);
    // The command line's preparation serves the starting field.
    // Unknown (null) until the server's own preparation is done (prepareAtStart).
    Json tets = nullptr, renderedCells = nullptr, prepareSeconds = nullptr;
    std::string device = resolvesToCuda(d.scene.rendererOptions.device) ? "cuda" : "cpu";
    const ViewState& first = d.scene.initial;
    if (first.width < kMinViewSize || first.height < kMinViewSize || first.width > kMaxViewSize ||
        first.height > kMaxViewSize)
        throwError(ErrorKind::Argument, "",
                   "image size " + std::to_string(first.width) + "x" +
                       std::to_string(first.height) + ": the viewer's sides are from " +
                       std::to_string(kMinViewSize) + " to " + std::to_string(kMaxViewSize) +
                       " pixels");
    d.meshStep = d.scene.initial.step;
    if (d.meshStep >= d.stepCount())
        throwError(
            ErrorKind::Argument, d.scene.file,
            "time step " + std::to_string(d.meshStep) + " of " + std::to_string(d.stepCount()));
    {
        const ScalarField values = selectScalarField(mesh, parseFieldSpec(d.scene.initial.field));
        FieldEntry& entry = d.fields[d.fieldKey(d.scene.initial.field, d.meshStep)];
        entry.range = finiteRange(values.values);
        entry.histogram = histogramOf(values.values, entry.range);
    }
    if (d.scene.renderer) {
        tets = d.scene.renderer->prepared().tets.tetCount();
        renderedCells = describeCells(d.scene.renderer->prepared().tets);
        prepareSeconds = d.scene.renderer->prepareSeconds();
        device = d.scene.renderer->deviceDescription();
        d.renderer = std::move(d.scene.renderer);
        d.rendererKey = d.fieldKey(d.scene.initial.field, d.meshStep);
    }
    d.infoBase = {{"type", "info"},
                  {"file", d.scene.file},
                  {"cells", mesh.cellCount()},
                  {"points", mesh.pointCount()},
                  {"tetrahedra", tets},
                  {"rendered_cells", renderedCells},
                  {"cell_types", types},
                  {"bounds", {{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}}},
                  {"fields", fields},
                  {"presets", presets},
                  {"methods", methodNames()},
                  {"settings", viewerVocabulary()},
                  {"device", device},
                  {"load_seconds", d.scene.loadSeconds},
                  {"prepare_seconds", prepareSeconds},
                  {"notes", d.scene.notes},
                  {"times", d.scene.series ? d.scene.series->times() : std::vector<double>{0.0}},
                  {"limits",
                   {{"max_message_bytes", d.opt.maxMessageBytes},
                    {"max_messages_per_second", d.opt.maxMessagesPerSecond},
                    {"min_size", kMinViewSize},
                    {"max_size", kMaxViewSize},
                    {"max_tf_points", kMaxTfPoints}}}};
}

ViewServer::~ViewServer() {
    stop();
    Impl& d = *impl_;
    if (d.renderThread.joinable()) d.renderThread.join();
    d.ioc.stop();
    if (d.ioThread.joinable()) d.ioThread.join();
}

void ViewServer::start() {
    Impl& d = *impl_;
    if (d.started) return;
    bindTo(d.acceptor, d.opt, true);
    d.boundPort = d.acceptor.local_endpoint().port();
    // Connections stay below the descriptor limit, so that accept rarely finds none left.
    d.connectionCap = d.opt.maxConnections;
    rlimit files{};
    if (getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur != RLIM_INFINITY)
        d.connectionCap = static_cast<int>(std::max<rlim_t>(
            1, std::min<rlim_t>(d.connectionCap, files.rlim_cur > kReservedDescriptors
                                                     ? files.rlim_cur - kReservedDescriptors
                                                     : 1)));
    d.acceptLoop();
    d.started = true;
    d.ioThread = std::thread([&d] { d.ioc.run(); });
    d.renderThread = std::thread([&d] { d.renderLoop(); });
}

std::uint16_t ViewServer::port() const {
    return impl_->boundPort;
}

const std::string& ViewServer::token() const {
    return impl_->opt.token;
}

std::string ViewServer::url() const {
    std::string host = impl_->opt.host;
    if (host == "0.0.0.0" || host == "::") {
        char name[256] = {};
        host = gethostname(name, sizeof name - 1) == 0 && name[0] ? name : "localhost";
    } else if (host.find(':') != std::string::npos) {
        host = "[" + host + "]";
    }
    return "http://" + host + ":" + std::to_string(port()) + "/?token=" + token();
}

void ViewServer::run(bool handleSignals) {
    Impl& d = *impl_;
    if (handleSignals) {
        // Before start: the network thread then owns the signals from its first moment.
        d.signals.emplace(d.ioc, SIGINT, SIGTERM);
        d.signals->async_wait([&d](beast::error_code ec, int signal) {
            if (ec) return;
            d.say(std::string("view: ") + (signal == SIGINT ? "interrupted" : "terminated") +
                  ": shutting down");
            d.requestStop();
        });
    }
    start();
    {
        std::unique_lock lk(d.m);
        d.cv.wait(lk, [&d] { return d.stopping; });
    }
    if (d.renderThread.joinable()) d.renderThread.join();
    // Close the listening socket and every connection, then let the network thread finish.
    net::post(d.ioc, [&d] {
        beast::error_code ignored;
        d.acceptor.close(ignored);
        d.acceptRetry.cancel();
        if (d.signals) d.signals->cancel(ignored);
        std::lock_guard lk(d.m);
        for (const auto& w : d.sessions)
            if (auto s = w.lock()) s->shutdown();
    });
    // Let the network thread close them, then stop it.
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    d.ioc.stop();
    if (d.ioThread.joinable()) d.ioThread.join();
}

void ViewServer::stop() {
    impl_->requestStop();
}

}  // namespace uvr::server
