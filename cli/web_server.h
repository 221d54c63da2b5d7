// The sockets of `deltagi serve` (serve_command.cpp): an HTTP server for the page's files and one WebSocket
// endpoint, /ws, on Boost.Beast over Asio (Debian: libboost-dev, header-only).
//
// It bounds what a peer can make it hold or wait for, whoever the peer is:
// - a request's header (8 KiB) and body (16 KiB) are bounded, and a request must arrive whole within the
//   request timeout (5 s); slow peers hold no thread (the sockets are asynchronous, served by two threads);
// - connections are bounded in all (512) and per peer address (128); one over either is closed at once;
// - a WebSocket message larger than its bound is refused from its frame header, before its payload is read
//   (the socket is closed with 1009, "message too big"), fragments included; a text message that is not UTF-8
//   closes its socket with 1007, as RFC 6455 asks;
// - nothing a socket sends waits in a queue here: when a write is done, the socket asks its owner for the
// next
//   message (`WebServer::Handlers::open`), which keeps only what is worth sending.
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace deltagi::cli {

struct HttpRequest {
    std::string method;
    std::string path;  // the target without its query
    std::optional<std::string> host, origin;
    std::string peer;  // the peer's address
};

struct HttpResponse {
    int status = 200;
    std::string contentType = "text/plain";
    std::string body;
    std::vector<std::pair<std::string, std::string>> headers;  // besides Content-Type and Content-Length
};

struct WebSocketMessage {
    bool binary = false;
    std::shared_ptr<const std::string> data;
};

// One open WebSocket; its member functions may be called from any thread.
class WebSocket {
  public:
    virtual ~WebSocket() = default;
    // Asks the socket to write what its owner's `next` gives, one message after another, until it gives
    // nothing.
    virtual void wake() = 0;
};

class WebServer {
  public:
    struct Limits {
        size_t maxMessageBytes = 16 * 1024;  // a WebSocket message, put together from its fragments
        size_t maxConnections = 512;
        size_t maxConnectionsPerPeer = 128;
        std::chrono::milliseconds requestTimeout{5000};
    };
    // Called on the server's threads (several at once for different sockets, one at a time for one socket).
    struct Handlers {
        std::function<HttpResponse(const HttpRequest&)> request;
        // Whether an upgrade request at /ws may open a WebSocket (false: 403).
        std::function<bool(const HttpRequest&)> acceptWebSocket;
        // A WebSocket opened; returns its `next`: the message to write next, or none for now.
        std::function<std::function<std::optional<WebSocketMessage>()>(const std::shared_ptr<WebSocket>&)>
            open;
        std::function<void(const std::shared_ptr<WebSocket>&, bool binary, std::string_view data)> message;
        // The socket closed (the peer left or broke the protocol); `next` is not called again.
        std::function<void(const std::shared_ptr<WebSocket>&)> close;
    };

    // Listens on address:port (port 0: any free one); InputError naming them when it cannot.
    WebServer(const std::string& address, int port, const Limits& limits, Handlers handlers);
    ~WebServer();  // stop()
    WebServer(const WebServer&) = delete;
    WebServer& operator=(const WebServer&) = delete;

    int port() const;
    // Closes every connection and joins the server's threads; no handler is called after it returns.
    void stop();

    struct Impl;  // web_server.cpp

  private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace deltagi::cli
