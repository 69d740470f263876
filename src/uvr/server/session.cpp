// SPDX-License-Identifier: MIT
#include "session.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "uvr/core/error.h"
#include "uvr/core/text.h"

namespace uvr::server {

namespace {

/// Messages waiting to be written to one connection before it counts as not reading.
constexpr std::size_t kMaxOutbox = 256;

std::string fmtSeconds(double s) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", s);
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

}  // namespace

void Session::start(http::request<http::string_body> req) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(server_.opt.maxMessageBytes);
    ws_.async_accept(req,
                     [self = shared_from_this()](beast::error_code ec) { self->onAccept(ec); });
}

void Session::sendText(std::string text, std::string_view supersedes) {
    queue(false, std::move(text), false, supersedes);
}

void Session::sendImage(std::string meta, std::string bytes) {
    queue(false, std::move(meta), false);
    queue(true, std::move(bytes), true);
}

void Session::shutdown() {
    closed_ = true;
    beast::error_code ignored;
    auto& socket = beast::get_lowest_layer(ws_).socket();
    socket.shutdown(tcp::socket::shutdown_both, ignored);
    socket.close(ignored);
}

void Session::sendError(const std::string& message, const std::string& request) {
    sendText(Json{{"type", "error"},
                  {"message", printableShort(message, kMaxErrorBytes)},
                  {"request", request}}
                 .dump(-1, ' ', false, Json::error_handler_t::replace));
}

void Session::onAccept(beast::error_code ec) {
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

std::size_t Session::liveSessionsLocked() {
    auto& v = server_.sessions;
    v.erase(std::remove_if(v.begin(), v.end(), [](const auto& w) { return w.expired(); }), v.end());
    return v.size();
}

std::string Session::endpointName() {
    beast::error_code ec;
    const auto ep = beast::get_lowest_layer(ws_).socket().remote_endpoint(ec);
    return ec ? "a client" : ep.address().to_string() + ":" + std::to_string(ep.port());
}

void Session::doRead() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
        self->onRead(ec);
    });
}

void Session::onRead(beast::error_code ec) {
    if (ec) {
        if (ec == websocket::error::message_too_big)
            server_.say("view: " + peer + " sent a message over " +
                        std::to_string(server_.opt.maxMessageBytes) + " bytes: connection closed");
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

bool Session::admit() {
    const auto now = Clock::now();
    const double rate = server_.opt.maxMessagesPerSecond;
    tokens_ =
        std::min(rate, tokens_ + rate * std::chrono::duration<double>(now - lastRefill_).count());
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

void Session::handle(const std::string& text) {
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
            throwError(ErrorKind::Argument, "", "expected a JSON object with a \"type\" string");
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

void Session::refused(const std::string& message, const std::string& type, const Json& msg) {
    Json e = {{"type", "error"},
              {"message", printableShort(message, kMaxErrorBytes)},
              {"request", printableShort(type, 40)}};
    if (msg.is_object())
        if (auto it = msg.find("seq"); it != msg.end() && it->is_number_unsigned()) e["seq"] = *it;
    sendText(e.dump(-1, ' ', false, Json::error_handler_t::replace));
    if (type == "set" || type == "reset_camera") sendState();
}

void Session::checkChangeKeys(const Json& msg) {
    if (auto it = msg.find("seq"); it != msg.end() && !it->is_number_unsigned())
        throwError(ErrorKind::Argument, "", "\"seq\": expected a non-negative integer");
    if (auto it = msg.find("interactive"); it != msg.end() && !it->is_boolean())
        throwError(ErrorKind::Argument, "", "\"interactive\": expected true or false");
}

void Session::markChanged(const Json& msg) {
    if (auto it = msg.find("seq"); it != msg.end()) seq = it->get<std::uint64_t>();
    demand.changed(msg.value("interactive", false), Clock::now());
}

void Session::onSet(const Json& msg) {
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

void Session::onResetCamera(const Json& msg) {
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
        Camera cam = resetCamera(server_.scene.bounds, float(state.width) / float(state.height));
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

void Session::onPing(const Json& msg) {
    Json seqValue;
    if (auto it = msg.find("seq"); it != msg.end()) {
        if (!it->is_number_unsigned())
            throwError(ErrorKind::Argument, "", "\"seq\": expected a non-negative integer");
        seqValue = *it;
    }
    sendText(Json{{"type", "pong"}, {"seq", seqValue}}.dump());
}

void Session::onSnapshot() {
    {
        std::lock_guard lk(server_.m);
        demand.snapshot = true;
    }
    server_.cv.notify_all();
}

void Session::onExport() {
    ViewState s;
    {
        std::lock_guard lk(server_.m);
        s = state;
    }
    sendText(server_.exportMessage(s).dump(-1, ' ', false, Json::error_handler_t::replace),
             "export");
}

void Session::sendState() {
    Json j;
    {
        std::lock_guard lk(server_.m);
        j = {{"type", "state"}, {"state", toJson(state)}};
    }
    sendText(j.dump(-1, ' ', false, Json::error_handler_t::replace), "state");
}

void Session::queue(bool binary, std::string data, bool endsFrame, std::string_view kind) {
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

void Session::pump() {
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

void Session::onWrite(beast::error_code ec) {
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

void Session::frameDone() {
    {
        std::lock_guard lk(server_.m);
        demand.finished();
    }
    server_.cv.notify_all();
}

}  // namespace uvr::server
