// The sockets of `deltagi serve` on Boost.Beast (web_server.h). Every connection lives on a strand of its
// own: its handlers run one at a time, those of different connections on either of the two threads.
#include "web_server.h"

#include <map>
#include <mutex>
#include <thread>

#include <fmt/core.h>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "deltagi/error.h"

namespace deltagi::cli {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

constexpr size_t kMaxHeaderBytes = 8 * 1024;
constexpr size_t kMaxBodyBytes = 16 * 1024;     // the page sends none; a small one is read and left alone
constexpr size_t kKeptBufferBytes = 64 * 1024;  // a socket's read buffer shrinks back after a larger message
constexpr int kThreads = 2;

}  // namespace

struct WebServer::Impl {
    Limits limits;
    Handlers handlers;

    // The connections open, in all and per peer address.
    std::mutex mutex;
    size_t connections = 0;
    std::map<std::string, size_t> perPeer;

    asio::io_context io{kThreads};
    tcp::acceptor acceptor{io};
    asio::steady_timer retry{io};
    std::vector<std::thread> threads;
    int port = 0;
    bool stopped = false;

    // A connection's share of the limits, given back when the last of its sessions ends.
    class Slot {
      public:
        Slot(Impl& impl, std::string peer) : impl_(impl), peer_(std::move(peer)) {}
        ~Slot() {
            std::lock_guard lock(impl_.mutex);
            --impl_.connections;
            if (--impl_.perPeer[peer_] == 0) impl_.perPeer.erase(peer_);
        }
        const std::string& peer() const { return peer_; }

      private:
        Impl& impl_;
        std::string peer_;
    };

    std::shared_ptr<Slot> take(const std::string& peer) {
        std::lock_guard lock(mutex);
        size_t& count = perPeer[peer];
        if (connections >= limits.maxConnections || count >= limits.maxConnectionsPerPeer) {
            if (count == 0) perPeer.erase(peer);
            return nullptr;
        }
        ++connections;
        ++count;
        return std::make_shared<Slot>(*this, peer);
    }

    void accept();
};

namespace {

using Impl = WebServer::Impl;

class WebSocketSession final : public WebSocket, public std::enable_shared_from_this<WebSocketSession> {
  public:
    WebSocketSession(beast::tcp_stream stream, std::shared_ptr<Impl::Slot> slot, Impl& server)
        : ws_(std::move(stream)), slot_(std::move(slot)), server_(server) {}

    void run(http::request<http::string_body> request) {
        request_ = std::move(request);
        beast::get_lowest_layer(ws_).expires_never();  // the stream's own timeouts from here on
        auto timeout = websocket::stream_base::timeout::suggested(beast::role_type::server);
        timeout.handshake_timeout = server_.limits.requestTimeout;
        ws_.set_option(timeout);
        ws_.read_message_max(server_.limits.maxMessageBytes);
        ws_.auto_fragment(false);
        ws_.async_accept(request_, [self = shared_from_this()](beast::error_code error) {
            if (!error) self->onOpen();
        });
    }

    void wake() override {
        asio::post(ws_.get_executor(), [self = shared_from_this()] { self->writeNext(); });
    }

  private:
    void onOpen() {
        open_ = true;
        next_ = server_.handlers.open(shared_from_this());
        read();
        writeNext();
    }

    void read() {
        ws_.async_read(buffer_,
                       [self = shared_from_this()](beast::error_code error, size_t) { self->onRead(error); });
    }

    void onRead(beast::error_code error) {
        if (error) {  // the peer left or broke the protocol (too big, not UTF-8, not masked): Beast closed it
            finish();
            return;
        }
        const auto data = buffer_.cdata();
        server_.handlers.message(shared_from_this(), ws_.got_binary(),
                                 std::string_view(static_cast<const char*>(data.data()), data.size()));
        buffer_.clear();
        if (buffer_.capacity() > kKeptBufferBytes) buffer_.shrink_to_fit();
        read();
    }

    void writeNext() {
        if (!open_ || closed_ || writing_ || !next_) return;
        std::optional<WebSocketMessage> message = next_();
        if (!message || !message->data) return;
        writing_ = std::move(message);
        ws_.binary(writing_->binary);
        ws_.async_write(asio::buffer(*writing_->data),
                        [self = shared_from_this()](beast::error_code error, size_t) {
                            self->writing_.reset();
                            if (!error) self->writeNext();
                        });
    }

    void finish() {
        if (closed_) return;
        closed_ = true;
        next_ = nullptr;
        server_.handlers.close(shared_from_this());
    }

    websocket::stream<beast::tcp_stream> ws_;
    std::shared_ptr<Impl::Slot> slot_;
    Impl& server_;
    http::request<http::string_body> request_;
    beast::flat_buffer buffer_;
    std::function<std::optional<WebSocketMessage>()> next_;
    std::optional<WebSocketMessage> writing_;
    bool open_ = false, closed_ = false;
};

class HttpSession final : public std::enable_shared_from_this<HttpSession> {
  public:
    HttpSession(tcp::socket socket, std::shared_ptr<Impl::Slot> slot, Impl& server)
        : stream_(std::move(socket)), slot_(std::move(slot)), server_(server) {}

    void run() {
        parser_.header_limit(kMaxHeaderBytes);
        parser_.body_limit(kMaxBodyBytes);
        stream_.expires_after(server_.limits.requestTimeout);  // the whole request, however slowly it comes
        http::async_read(
            stream_, buffer_, parser_,
            [self = shared_from_this()](beast::error_code error, size_t) { self->onRead(error); });
    }

  private:
    void onRead(beast::error_code error) {
        if (error == http::error::header_limit) return respond({431, "text/plain", "header too large\n", {}});
        if (error == http::error::body_limit) return respond({413, "text/plain", "body too large\n", {}});
        if (error) return;  // timed out, malformed or gone: the connection closes
        http::request<http::string_body>& message = parser_.get();
        HttpRequest request;
        const auto text = [](beast::string_view view) { return std::string(view.data(), view.size()); };
        request.method = text(message.method_string());
        request.path = text(message.target());
        request.path.resize(std::min(request.path.size(), request.path.find('?')));
        if (auto it = message.find(http::field::host); it != message.end()) request.host = text(it->value());
        if (auto it = message.find(http::field::origin); it != message.end())
            request.origin = text(it->value());
        request.peer = slot_->peer();
        if (websocket::is_upgrade(message)) {
            if (request.path == "/ws" && server_.handlers.acceptWebSocket(request)) {
                std::make_shared<WebSocketSession>(std::move(stream_), std::move(slot_), server_)
                    ->run(parser_.release());
                return;
            }
            return respond({403, "text/plain", "deltagi serve: WebSocket refused\n", {}});
        }
        HttpResponse response;
        try {
            response = server_.handlers.request(request);
        } catch (const std::exception& e) {
            response = {500, "text/plain", std::string(e.what()) + "\n", {}};
        }
        respond(response, message.method() == http::verb::head);
    }

    void respond(const HttpResponse& response, bool head = false) {
        auto message = std::make_shared<http::response<http::string_body>>();
        message->result(static_cast<unsigned>(response.status));
        message->version(11);
        message->set(http::field::content_type, response.contentType);
        message->set(http::field::cache_control, "no-store");
        message->set("X-Content-Type-Options", "nosniff");
        for (const auto& [name, value] : response.headers) message->set(name, value);
        message->keep_alive(false);
        if (head) {
            message->content_length(response.body.size());
        } else {
            message->body() = response.body;
            message->prepare_payload();
        }
        stream_.expires_after(server_.limits.requestTimeout);
        http::async_write(stream_, *message, [self = shared_from_this(), message](beast::error_code, size_t) {
            beast::error_code ignored;
            self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
        });
    }

    beast::tcp_stream stream_;
    std::shared_ptr<Impl::Slot> slot_;
    Impl& server_;
    beast::flat_buffer buffer_;
    http::request_parser<http::string_body> parser_;
};

}  // namespace

void WebServer::Impl::accept() {
    acceptor.async_accept(asio::make_strand(io), [this](beast::error_code error, tcp::socket socket) {
        if (error == asio::error::operation_aborted) return;
        if (error) {  // out of file descriptors, say: try again shortly rather than spin
            retry.expires_after(std::chrono::milliseconds(50));
            retry.async_wait([this](beast::error_code e) {
                if (!e) accept();
            });
            return;
        }
        beast::error_code ignored;
        const tcp::endpoint peer = socket.remote_endpoint(ignored);
        if (std::shared_ptr<Slot> slot = take(peer.address().to_string()))
            std::make_shared<HttpSession>(std::move(socket), std::move(slot), *this)->run();
        else
            socket.close(ignored);  // over the limits: closed at once
        accept();
    });
}

WebServer::WebServer(const std::string& address, int port, const Limits& limits, Handlers handlers)
    : impl_(std::make_unique<Impl>()) {
    impl_->limits = limits;
    impl_->handlers = std::move(handlers);
    const std::string where = address.find(':') != std::string::npos
                                  ? fmt::format("serve: [{}]:{}", address, port)
                                  : fmt::format("serve: {}:{}", address, port);
    beast::error_code error;
    const asio::ip::address ip =
        asio::ip::make_address(address == "localhost" ? "127.0.0.1" : address, error);
    if (error) throw InputError(where, "--host: not an IPv4 or IPv6 address");
    const tcp::endpoint endpoint(ip, static_cast<unsigned short>(port));
    tcp::acceptor& acceptor = impl_->acceptor;
    acceptor.open(endpoint.protocol(), error);
    if (!error) acceptor.set_option(asio::socket_base::reuse_address(true), error);
    if (!error) acceptor.bind(endpoint, error);
    if (!error) acceptor.listen(asio::socket_base::max_listen_connections, error);
    if (error)
        throw InputError(where,
                         fmt::format("cannot listen: {} (is the port in use? --port 0 takes any free one)",
                                     error.message()));
    impl_->port = acceptor.local_endpoint().port();
    impl_->accept();
    for (int i = 0; i < kThreads; ++i)
        impl_->threads.emplace_back([impl = impl_.get()] {
            for (;;) {
                try {
                    impl->io.run();
                    return;
                } catch (const std::exception&
                             e) {  // a handler failed: that connection is dropped, not the server
                    fmt::print(stderr, "deltagi serve: {}\n", e.what());
                }
            }
        });
}

WebServer::~WebServer() {
    stop();
}

int WebServer::port() const {
    return impl_->port;
}

void WebServer::stop() {
    if (impl_->stopped) return;
    impl_->stopped = true;
    impl_->io.stop();
    for (std::thread& thread : impl_->threads) thread.join();
}

}  // namespace deltagi::cli
