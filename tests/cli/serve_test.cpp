// `deltagi serve` over its sockets (a Boost.Beast WebSocket client and plain TCP): the server stays up and
// answers through malformed messages, text that is not UTF-8, a scene file whose name is not, a huge message
// and slow or idle connections; it answers only requests that name it (Host) from its own page (Origin), on
// every address it listens on.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <fstream>
#include <mutex>
#include <random>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "test_cli.h"

namespace deltagi::test {
namespace {

namespace fs = std::filesystem;
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using nlohmann::json;
using tcp = asio::ip::tcp;

// `deltagi serve ARGS --port 0` started in `dir`, stopped by SIGTERM when it goes.
class Server {
  public:
    Server(std::vector<std::string> args, const fs::path& dir) : dir_(dir) {
        args.insert(args.end(), {"--port", "0"});
        pid_ = startCli(args, dir);
        const std::regex url(R"(http://[^/]*:(\d+)/)");
        const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(120);
        while (std::chrono::steady_clock::now() < end && alive()) {
            std::smatch m;
            const std::string out = readText(dir / "stdout.txt");
            if (std::regex_search(out, m, url)) {
                port_ = std::stoi(m[1]);
                return;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        ADD_FAILURE() << "no URL from deltagi serve: " << readText(dir / "stderr.txt");
    }
    ~Server() {
        if (pid_ > 0 && alive()) {
            kill(pid_, SIGTERM);
            int status = 0;
            waitpid(pid_, &status, 0);
        }
    }
    int port() const { return port_; }
    pid_t pid() const { return pid_; }
    bool alive() const {
        int status = 0;
        return pid_ > 0 && waitpid(pid_, &status, WNOHANG) == 0;
    }
    std::string stderrText() const { return readText(dir_ / "stderr.txt"); }

  private:
    fs::path dir_;
    pid_t pid_ = -1;
    int port_ = 0;
};

// The status code of `GET path` sent to address:port with these Host and Origin headers (Origin left out
// when empty); 0 when no answer came.
int connectTo(const std::string& address, int port);

int httpStatus(const std::string& address, int port, const std::string& host, const std::string& origin,
               const std::string& path = "/") {
    const int fd = connectTo(address, port);
    if (fd < 0) return 0;
    std::string request = "GET " + path + " HTTP/1.1\r\nHost: " + host + "\r\n";
    if (!origin.empty()) request += "Origin: " + origin + "\r\n";
    request += "Connection: close\r\n\r\n";
    (void)!write(fd, request.data(), request.size());
    char reply[64] = {};
    const ssize_t got = read(fd, reply, sizeof reply - 1);
    close(fd);
    int status = 0;
    if (got > 12 && std::sscanf(reply, "HTTP/1.%*d %d", &status) == 1) return status;
    return 0;
}

// A TCP connection to address:port (-1 when none), reads giving up after 10 s.
int connectTo(const std::string& address, int port) {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<uint16_t>(port));
    inet_pton(AF_INET, address.c_str(), &to.sin_addr);
    timeval timeout{10, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &timeout, sizeof timeout);
    if (connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

// A WebSocket client (Boost.Beast, on a thread of its own) that keeps the text messages it receives.
class Socket {
  public:
    // Opens ws://address:port/ws with Host address:port and this Origin (none when empty).
    Socket(const std::string& address, int port, const std::string& origin) {
        beast::error_code error;
        beast::get_lowest_layer(ws_).connect(tcp::endpoint(asio::ip::make_address(address), port), error);
        if (error) return;
        ws_.set_option(websocket::stream_base::decorator([origin](websocket::request_type& request) {
            if (!origin.empty()) request.set(http::field::origin, origin);
        }));
        ws_.handshake(address + ":" + std::to_string(port), "/ws", error);
        if (error) return;
        open_ = true;
        read();
        thread_ = std::thread([this] { io_.run(); });
    }
    ~Socket() {
        io_.stop();
        if (thread_.joinable()) thread_.join();
    }
    bool open() const { return open_; }
    // Sends one message, after those sent before.
    void send(bool binary, std::string bytes) {
        asio::post(io_, [this, binary, bytes = std::move(bytes)]() mutable {
            outgoing_.emplace_back(binary, std::move(bytes));
            if (outgoing_.size() == 1) write();
        });
    }
    std::vector<std::string> texts() {
        std::lock_guard lock(mutex_);
        return texts_;
    }
    // The close code the server gave, once it closed the socket (0 before).
    int closedWith() {
        std::lock_guard lock(mutex_);
        return closedWith_;
    }

  private:
    void read() {
        ws_.async_read(buffer_, [this](beast::error_code error, size_t) {
            std::lock_guard lock(mutex_);
            if (error) {
                closedWith_ = ws_.reason().code ? ws_.reason().code : -1;
                return;
            }
            if (ws_.got_text()) texts_.push_back(beast::buffers_to_string(buffer_.data()));
            buffer_.clear();
            read();
        });
    }
    void write() {
        ws_.binary(outgoing_.front().first);
        ws_.async_write(asio::buffer(outgoing_.front().second), [this](beast::error_code error, size_t) {
            outgoing_.pop_front();
            if (!error && !outgoing_.empty()) write();
        });
    }

    asio::io_context io_;
    websocket::stream<beast::tcp_stream> ws_{io_};
    beast::flat_buffer buffer_;
    std::deque<std::pair<bool, std::string>> outgoing_;
    bool open_ = false;
    std::thread thread_;
    std::mutex mutex_;
    std::vector<std::string> texts_;
    int closedWith_ = 0;
};

// The peak resident memory of process `pid` (VmHWM), in bytes.
int64_t peakMemory(pid_t pid) {
    return std::stoll(procStatus(pid, "VmHWM")) * 1024;
}

using ServeTest = CliTest;

TEST_F(ServeTest, StaysUpThroughMalformedMessagesAndBytesThatAreNotUtf8) {
    // A scene file whose name is not UTF-8: the page's state and /scene.json name it.
    const fs::path scene = dir_ / "sc\xffne.json";
    writeText(scene, tinyScene().dump());
    Server server({"serve", scene.string(), "--set", "options.volume.resolution=16"}, dir_);
    ASSERT_GT(server.port(), 0);
    const std::string origin = "http://127.0.0.1:" + std::to_string(server.port());
    // Text that is not UTF-8 closes its socket (1007, RFC 6455), and only that one.
    for (const std::string& bytes :
         {std::string("\xff\xfe"),
          std::string(R"({"type": ")"
                      "\xff"
                      R"("})"),
          R"({"type": "drag", "object": 0, "x": ")" + std::string(40, '\xc3') + R"(", "y": 1})"}) {
        Socket bad("127.0.0.1", server.port(), origin);
        ASSERT_TRUE(bad.open());
        bad.send(false, bytes);
        EXPECT_TRUE(waitFor([&] { return bad.closedWith() != 0; }));
        EXPECT_EQ(bad.closedWith(), 1007);
    }
    Socket socket("127.0.0.1", server.port(), origin);
    ASSERT_TRUE(socket.open());
    std::vector<std::string> messages = {
        // Errors that quote the value or the keys, cut where a two- or three-byte character is cut.
        R"({"type": "drag", "object": 0, "x": "ééééééééééééééééééééééééééééééééééééééé", "y": 1})",
        R"({"type": "options", "values": {")" + std::string(30, 'k') + "€€€€€€€" + R"(": 1}})",
    };
    std::mt19937 random(7);
    const std::string alphabet = "{}[]\":,.0123456789-+eE truefalsnl\\/éß€\t\n";
    for (int i = 0; i < 1000; ++i) {
        std::string bytes;
        for (size_t n = 1 + random() % 200; bytes.size() < n;) {
            const size_t at = random() % alphabet.size();
            size_t length = 1;  // whole characters only
            while (at + length < alphabet.size() && (alphabet[at + length] & 0xc0) == 0x80) ++length;
            if ((alphabet[at] & 0xc0) != 0x80) bytes += alphabet.substr(at, length);
        }
        messages.push_back(std::move(bytes));
    }
    for (std::string& m : messages) socket.send(false, std::move(m));
    socket.send(true, "not a camera frame");
    EXPECT_TRUE(waitFor([&] { return socket.texts().size() >= 20; })) << socket.texts().size();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    ASSERT_TRUE(server.alive()) << server.stderrText();
    EXPECT_EQ(socket.closedWith(), 0);
    EXPECT_EQ(httpStatus("127.0.0.1", server.port(), "127.0.0.1", ""), 200);
    EXPECT_EQ(httpStatus("127.0.0.1", server.port(), "127.0.0.1", "", "/scene.json"), 200);
    int errors = 0;
    for (const std::string& text : socket.texts()) {
        json message;
        ASSERT_NO_THROW(message = json::parse(text)) << text;  // parsing checks the UTF-8
        if (message["type"] == "error") ++errors;
        if (message["type"] == "state") EXPECT_NE(message.dump().find("sc\xef\xbf\xbdne"), std::string::npos);
    }
    EXPECT_GT(errors, 10);
    EXPECT_TRUE(server.alive()) << server.stderrText();
}

// One message of 300 MiB is refused from its frame header, before its payload is read: the server's peak
// memory grows by less than 20 MB and it goes on answering.
TEST_F(ServeTest, RefusesAHugeMessageBeforeReadingIt) {
    writeText(dir_ / "scene.json", tinyScene().dump());
    Server server({"serve", (dir_ / "scene.json").string(), "--set", "options.volume.resolution=16"}, dir_);
    ASSERT_GT(server.port(), 0);
    const std::string host = "127.0.0.1:" + std::to_string(server.port());
    {
        Socket first("127.0.0.1", server.port(), "http://" + host);
        ASSERT_TRUE(first.open());
        // Its first frame rendered, the server's memory is what it is while it waits.
        EXPECT_TRUE(waitFor([&] {
            for (const std::string& text : first.texts())
                if (text.find(R"("type":"frame")") != std::string::npos) return true;
            return false;
        }));
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
    const int64_t before = peakMemory(server.pid());
    const int fd = connectTo("127.0.0.1", server.port());
    ASSERT_GE(fd, 0);
    const std::string upgrade =
        "GET /ws HTTP/1.1\r\nHost: " + host + "\r\nOrigin: http://" + host +
        "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n";
    ASSERT_EQ(write(fd, upgrade.data(), upgrade.size()), static_cast<ssize_t>(upgrade.size()));
    std::string reply;
    char c = 0;
    while (reply.find("\r\n\r\n") == std::string::npos && read(fd, &c, 1) == 1) reply += c;
    ASSERT_EQ(reply.rfind("HTTP/1.1 101", 0), 0u) << reply;
    // A masked binary frame declaring 300 MiB, then as much of its payload as the server takes.
    const uint64_t size = 300ull << 20;
    std::string header = {'\x82', '\xff'};
    for (int shift = 56; shift >= 0; shift -= 8) header += static_cast<char>((size >> shift) & 0xff);
    header += std::string(4, '\x5a');
    ASSERT_EQ(write(fd, header.data(), header.size()), static_cast<ssize_t>(header.size()));
    const std::string chunk(1 << 20, 'x');
    uint64_t sent = 0;
    while (sent < size) {
        const ssize_t n = send(fd, chunk.data(), chunk.size(), MSG_NOSIGNAL);
        if (n <= 0) break;
        sent += static_cast<uint64_t>(n);
    }
    close(fd);
    EXPECT_LT(sent, size) << "the server read the whole message";
    const int64_t growth = peakMemory(server.pid()) - before;
    EXPECT_LT(growth, 20'000'000) << growth;
    ASSERT_TRUE(server.alive()) << server.stderrText();
    EXPECT_EQ(httpStatus("127.0.0.1", server.port(), host, ""), 200);
}

// 50 connections that send half a header and 50 that send nothing leave a good client answered; each gives up
// its connection after the request timeout.
TEST_F(ServeTest, AnswersThroughSlowAndIdleConnections) {
    writeText(dir_ / "scene.json", tinyScene().dump());
    Server server({"serve", (dir_ / "scene.json").string(), "--set", "options.volume.resolution=16"}, dir_);
    ASSERT_GT(server.port(), 0);
    std::vector<int> held;
    for (int i = 0; i < 100; ++i) {
        const int fd = connectTo("127.0.0.1", server.port());
        ASSERT_GE(fd, 0);
        if (i % 2 == 0) {
            const std::string part = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ";
            ASSERT_EQ(write(fd, part.data(), part.size()), static_cast<ssize_t>(part.size()));
        }
        held.push_back(fd);
    }
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(httpStatus("127.0.0.1", server.port(), "127.0.0.1", ""), 200);
    RecordProperty(
        "good_client_ms",
        static_cast<int>(
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count()));
    // The server closes them after its request timeout (5 s): a read sees the end.
    char byte = 0;
    EXPECT_EQ(read(held.front(), &byte, 1), 0);
    for (int fd : held) close(fd);
    EXPECT_TRUE(server.alive()) << server.stderrText();
}

TEST_F(ServeTest, AnswersOnlyItsOwnPageOnEveryAddress) {
    writeText(dir_ / "scene.json", tinyScene().dump());
    Server server({"serve", (dir_ / "scene.json").string(), "--host", "127.0.0.2", "--allow-host", "mybox",
                   "--set", "options.volume.resolution=16"},
                  dir_);
    ASSERT_GT(server.port(), 0);
    const std::string port = std::to_string(server.port());
    EXPECT_EQ(httpStatus("127.0.0.2", server.port(), "127.0.0.2:" + port, ""), 200);
    EXPECT_EQ(httpStatus("127.0.0.2", server.port(), "mybox:" + port, ""), 200);
    EXPECT_EQ(httpStatus("127.0.0.2", server.port(), "localhost:" + port, ""), 200);
    // A name that was made to point here (DNS rebinding), the wrong port, another site's page.
    EXPECT_EQ(httpStatus("127.0.0.2", server.port(), "evil.example:" + port, ""), 403);
    EXPECT_EQ(httpStatus("127.0.0.2", server.port(), "127.0.0.2:1", ""), 403);
    EXPECT_EQ(httpStatus("127.0.0.2", server.port(), "127.0.0.2:" + port, "http://evil.example"), 403);
    EXPECT_FALSE(Socket("127.0.0.2", server.port(), "http://evil.example").open());
    Socket own("127.0.0.2", server.port(), "http://127.0.0.2:" + port);
    EXPECT_TRUE(own.open());
    EXPECT_TRUE(waitFor([&] { return !own.texts().empty(); }));
}

}  // namespace
}  // namespace deltagi::test
