// SPDX-License-Identifier: MIT
#include "http_connection.h"

#include <algorithm>

#include "session.h"
#include "uvr/server/web_assets.h"

namespace uvr::server {

namespace {

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

}  // namespace

void HttpConnection::close() {
    beast::error_code ignored;
    stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
    stream_.close();
}

void HttpConnection::doRead() {
    parser_.emplace();
    parser_->header_limit(16 * 1024);
    parser_->body_limit(64 * 1024);
    stream_.expires_after(seconds(server_.opt.idleSeconds));
    http::async_read(
        stream_, buffer_, *parser_,
        [self = shared_from_this()](beast::error_code ec, std::size_t) { self->onRead(ec); });
}

bool HttpConnection::tokenIn(const http::request<http::string_body>& req, bool allowCookie) const {
    const std::string& token = server_.opt.token;
    if (auto q = queryValue(req.target(), "token"); q && sameSecret(*q, token)) return true;
    if (!allowCookie) return false;
    const auto it = req.find(http::field::cookie);
    if (it == req.end()) return false;
    const auto c = cookieValue(it->value(), cookieName());
    return c && sameSecret(*c, token);
}

void HttpConnection::onRead(beast::error_code ec) {
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
            v.erase(std::remove_if(v.begin(), v.end(), [](const auto& w) { return w.expired(); }),
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

void HttpConnection::respond(const http::request<http::string_body>& req, http::status status,
                             std::string body) {
    http::response<http::string_body> res{status, req.version()};
    res.set(http::field::content_type, "text/plain; charset=utf-8");
    res.set(http::field::cache_control, "no-store");
    res.body() = std::move(body);
    res.prepare_payload();
    res.keep_alive(req.keep_alive());
    write(std::move(res));
}

void HttpConnection::write(http::response<http::string_body>&& res) {
    auto sp = std::make_shared<http::response<http::string_body>>(std::move(res));
    http::async_write(stream_, *sp,
                      [self = shared_from_this(), sp](beast::error_code ec, std::size_t) {
                          if (ec) return;
                          if (!sp->keep_alive()) {
                              beast::error_code ignored;
                              self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                              return;
                          }
                          self->doRead();
                      });
}

}  // namespace uvr::server
