// SPDX-License-Identifier: MIT
#pragma once

#include <optional>
#include <string>

#include "server_internal.h"

namespace uvr::server {

/// One HTTP connection: serves the page and its files, or hands a WebSocket upgrade to a
/// Session.
class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
public:
    HttpConnection(ViewServer::Impl& server, tcp::socket&& socket)
        : server_(server), stream_(std::move(socket)) {}

    void start() { doRead(); }

    /// Ends the connection (to make room for a new one; network thread).
    void close();

private:
    void doRead();
    bool tokenIn(const http::request<http::string_body>& req, bool allowCookie) const;

    std::string cookieName() const { return "uvr_token_" + std::to_string(server_.boundPort); }

    void onRead(beast::error_code ec);

    void respond(const http::request<http::string_body>& req, http::status status,
                 std::string body);
    void write(http::response<http::string_body>&& res);
    ViewServer::Impl& server_;
    beast::tcp_stream stream_;
    beast::flat_buffer buffer_;
    std::optional<http::request_parser<http::string_body>> parser_;
};

}  // namespace uvr::server
