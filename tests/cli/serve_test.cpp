// `deltagi serve` over its sockets (civetweb's WebSocket client and plain HTTP requests): the server stays up
// and answers through malformed messages, text that is not UTF-8 and a scene file whose name is not; it
// answers only requests that name it (Host) from its own page (Origin), on every address it listens on.
#include <arpa/inet.h>
#include <civetweb.h>
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
#include <nlohmann/json.hpp>

#include "test_cli.h"

namespace deltagi::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

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
int httpStatus(const std::string& address, int port, const std::string& host, const std::string& origin,
               const std::string& path = "/") {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(static_cast<uint16_t>(port));
    inet_pton(AF_INET, address.c_str(), &to.sin_addr);
    timeval timeout{10, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
    if (connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
        close(fd);
        return 0;
    }
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

// A WebSocket client that keeps the text messages it receives.
class Socket {
  public:
    Socket(const std::string& address, int port, const std::string& origin) {
        mg_init_library(0);
        char error[256] = {};
        connection_ = mg_connect_websocket_client(address.c_str(), port, 0, error, sizeof error, "/ws",
                                                  origin.empty() ? nullptr : origin.c_str(), &Socket::onData,
                                                  nullptr, this);
    }
    ~Socket() {
        if (connection_) mg_close_connection(connection_);
    }
    bool open() const { return connection_ != nullptr; }
    void send(int opcode, const std::string& bytes) {
        mg_websocket_client_write(connection_, opcode, bytes.data(), bytes.size());
    }
    std::vector<std::string> texts() {
        std::lock_guard lock(mutex_);
        return texts_;
    }

  private:
    static int onData(mg_connection*, int bits, char* data, size_t size, void* self) {
        auto* socket = static_cast<Socket*>(self);
        if ((bits & 0xf) == MG_WEBSOCKET_OPCODE_TEXT) {
            std::lock_guard lock(socket->mutex_);
            socket->texts_.emplace_back(data, size);
        }
        return 1;
    }
    mg_connection* connection_ = nullptr;
    std::mutex mutex_;
    std::vector<std::string> texts_;
};

using ServeTest = CliTest;

TEST_F(ServeTest, StaysUpThroughMalformedMessagesAndBytesThatAreNotUtf8) {
    // A scene file whose name is not UTF-8: the page's state and /scene.json name it.
    const fs::path scene = dir_ / "sc\xffne.json";
    writeText(scene, tinyScene().dump());
    Server server({"serve", scene.string(), "--set", "options.volume.resolution=16"}, dir_);
    ASSERT_GT(server.port(), 0);
    Socket socket("127.0.0.1", server.port(), "http://127.0.0.1");
    ASSERT_TRUE(socket.open());
    std::vector<std::string> messages = {
        "\xff\xfe",
        R"({"type": ")"
        "\xff"
        R"("})",
        // An error that quotes the value, cut where a two-byte character is cut.
        R"({"type": "drag", "object": 0, "x": ")" + std::string(40, '\xc3') + R"(", "y": 1})",
        R"({"type": "drag", "object": 0, "x": "ééééééééééééééééééééééééééééééééééééééé", "y": 1})",
        R"({"type": "options", "values": {")" + std::string(30, 'k') +
            "\xe2\x82"
            R"(": 1}})",
    };
    std::mt19937 random(7);
    for (int i = 0; i < 1000; ++i) {
        std::string bytes(1 + random() % 200, '\0');
        for (char& c : bytes) c = static_cast<char>(random());
        messages.push_back(std::move(bytes));
    }
    for (const std::string& m : messages) socket.send(MG_WEBSOCKET_OPCODE_TEXT, m);
    socket.send(MG_WEBSOCKET_OPCODE_BINARY, "not a camera frame");
    EXPECT_TRUE(waitFor([&] { return socket.texts().size() >= 20; })) << socket.texts().size();
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    ASSERT_TRUE(server.alive()) << server.stderrText();
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
    Socket own("127.0.0.2", server.port(), "http://127.0.0.2");
    EXPECT_TRUE(own.open());
    EXPECT_TRUE(waitFor([&] { return !own.texts().empty(); }));
}

}  // namespace
}  // namespace deltagi::test
