// `deltagi serve`: the command, the web server's handlers, the sources of `live --serve` and the message
// handler of the session server (serve_server.h; its render thread is serve_render.cpp).
#include "serve_server.h"

#include <arpa/inet.h>

#include <bit>
#include <cmath>

#include <tbb/global_control.h>

#include "web_assets.h"

namespace deltagi::cli {
namespace serve {
namespace {

bool isLoopback(const std::string& host) {
    return host == "127.0.0.1" || host == "localhost" || host == "::1" || host == "[::1]";
}

// An IPv4 address, or an IPv6 one in brackets.
bool isAddress(const std::string& name) {
    in6_addr address{};
    if (name.size() > 2 && name.front() == '[' && name.back() == ']')
        return inet_pton(AF_INET6, name.substr(1, name.size() - 2).c_str(), &address) == 1;
    return inet_pton(AF_INET, name.c_str(), &address) == 1;
}

const char* contentType(const std::string& name) {
    if (name.ends_with(".html")) return "text/html; charset=utf-8";
    if (name.ends_with(".js")) return "text/javascript; charset=utf-8";
    if (name.ends_with(".css")) return "text/css; charset=utf-8";
    return "application/octet-stream";
}

}  // namespace

// Whatever address the server listens on, a request's Host names it by an address (a page of another site
// reaches it by an address only as itself: a site whose DNS name is made to point here, to read the session
// through the user's browser, sends that name), by "localhost" or by a name the user allowed (--allow-host),
// with this server's port or none; and a WebSocket's Origin, when given, is this server's page
// ("http://" + Host): a page of another site cannot open the session's socket.
bool Server::hostAllowed(const HttpRequest& request) const {
    if (!request.host) return false;
    const std::string& host = *request.host;
    std::string name = host, port;
    const size_t close = host.find(']');
    const size_t colon = host.rfind(':');
    if (colon != std::string::npos && (close == std::string::npos || colon > close)) {
        name = host.substr(0, colon);
        port = host.substr(colon + 1);
    }
    if (!port.empty() && port != std::to_string(port_)) return false;
    const bool named =
        name == "localhost" || isAddress(name) ||
        std::find(args_.allowedHosts.begin(), args_.allowedHosts.end(), name) != args_.allowedHosts.end();
    if (!named) return false;
    return !request.origin || *request.origin == "http://" + host;
}

// Only the page's own files and two generated downloads; no name from a request reaches the file system.
HttpResponse Server::onRequest(const HttpRequest& request) {
    if (!hostAllowed(request))
        return {403,
                "text/plain",
                "deltagi serve: unexpected Host or Origin (open the page by this machine's address, "
                "localhost, or "
                "a name given with --allow-host)\n",
                {}};
    if (request.method != "GET" && request.method != "HEAD") return {405, "text/plain", "GET only\n", {}};
    const std::string name = request.path == "/" ? "index.html" : request.path.substr(1);
    for (const assets::Asset& asset : assets::kAssets)
        if (name == asset.name)
            return {200,
                    contentType(name),
                    std::string(reinterpret_cast<const char*>(asset.data), asset.size),
                    {}};
    if (name == "scene.json") {
        std::string text;
        {
            std::lock_guard lock(sessionMutex_);
            text = live::jsonText(session_.document(), 2) + "\n";
        }
        return {
            200, "application/json", text, {{"Content-Disposition", "attachment; filename=\"scene.json\""}}};
    }
    if (name == "image.png") {
        std::shared_ptr<const Image> composite;
        bool refined = false;
        {
            std::lock_guard lock(sessionMutex_);
            composite = latestComposite_;
            refined = latestRefined_;
        }
        if (!composite) return {503, "text/plain", "no frame yet\n", {}};
        return {200,
                "image/png",
                live::encodePng(*composite),
                {{"Content-Disposition", "attachment; filename=\"image.png\""},
                 {"X-Deltagi-Refined", refined ? "1" : "0"}}};
    }
    return {404, "text/plain", "not found\n", {}};
}

bool Server::acceptWebSocket(const HttpRequest& request) {
    if (!hostAllowed(request)) return false;
    std::lock_guard lock(clientsMutex_);
    return clients_.size() < kMaxClients;
}

std::function<std::optional<WebSocketMessage>()> Server::onOpen(const std::shared_ptr<WebSocket>& socket) {
    std::shared_ptr<Client> client;
    {
        std::lock_guard lock(clientsMutex_);
        client = std::make_shared<Client>(socket, nextClient_++);
        clients_[socket.get()] = client;
    }
    json hello = {{"type", "hello"}, {"client", client->id()}};
    // The server's own camera (live --serve): the page shows its frames and offers none of its own.
    if (cameraFeed_) hello["camera"] = cameraFeed_->source().name();
    client->reply(live::jsonText(hello));
    {
        std::lock_guard lock(sessionMutex_);
        client->state(std::make_shared<const std::string>(live::jsonText(session_.state())));
        if (latestFrame_) client->frame(latestFrame_);
    }
    return [client] { return client->next(); };
}

// A message, put together from its fragments by the web server, which refuses one over kMaxCameraFrameBytes
// from its header; a text message is checked further by the session (16 KiB, JSON).
void Server::onMessage(const std::shared_ptr<WebSocket>& socket, bool binary, std::string_view data) {
    std::shared_ptr<Client> client;
    {
        std::lock_guard lock(clientsMutex_);
        auto it = clients_.find(socket.get());
        if (it == clients_.end()) return;
        client = it->second;
    }
    if (binary) {
        onCameraFrame(client, data);
        return;
    }
    if (data.size() > live::kMaxMessageBytes) {  // refused as the handler refuses it, without a copy
        client->reply(live::jsonText(json{{"type", "error"},
                                          {"message", fmt::format("message: {} bytes, more than {}",
                                                                  data.size(), live::kMaxMessageBytes)}}));
        return;
    }
    std::lock_guard lock(inboxMutex_);
    if (inbox_.size() >= kMaxWaitingMessages) {
        client->reply(live::jsonText(
            json{{"type", "error"}, {"message", "message: too many messages waiting; dropped"}}));
        return;
    }
    inbox_.push_back({client, std::string(data)});
    inboxWake_.notify_one();
}

// A page's camera frame: a JPEG, or the page's own form, "DGIT" and the time it was taken (a little-endian
// float64, milliseconds on the page's clock) before the JPEG. The pose filter takes that time (on the
// server's clock from the page's first such frame on) instead of the arrival, which the page's encoding and a
// loaded machine delay unevenly: frames that arrive in a burst after a stall are not frames taken a moment
// apart (the prior that holds an uncertain pose near the last one would hold it where the camera no longer
// is).
void Server::onCameraFrame(const std::shared_ptr<Client>& client, std::string_view data) {
    constexpr std::string_view kTimed = "DGIT";
    constexpr size_t kTimedHeader = kTimed.size() + 8;
    const int64_t number = ++client->cameraFrames;
    CameraInput input;
    input.arrived = Clock::now();
    input.timeSeconds = std::chrono::duration<double>(input.arrived - started_).count();
    if (data.size() >= kTimedHeader && data.substr(0, kTimed.size()) == kTimed) {
        uint64_t bits = 0;
        for (size_t b = 0; b < 8; ++b)
            bits |= static_cast<uint64_t>(static_cast<uint8_t>(data[kTimed.size() + b])) << (8 * b);
        const double takenSeconds = std::bit_cast<double>(bits) / 1000.0;
        data.remove_prefix(kTimedHeader);
        if (std::isfinite(takenSeconds)) {
            if (!client->cameraClockOffset) client->cameraClockOffset = input.timeSeconds - takenSeconds;
            input.timeSeconds = takenSeconds + *client->cameraClockOffset;
        }
    }
    input.jpeg.assign(data);
    input.client = client;
    input.clientId = client->id();
    input.number = number;
    std::lock_guard lock(sessionMutex_);
    if (cameraInput_) ++cameraDropped_;
    cameraInput_ = std::move(input);
    changed_.notify_all();
}

void Server::openFeeds() {
    if (args_.camera.empty()) return;
    const Scene& scene = session_.scene();
    if (!tracker_)
        throw InputError(args_.scene.string(),
                         "markers: the scene places no marker to register the camera by");
    cameraFeed_.emplace(openFrameSource(args_.camera, args_.patternFps), true);
    checkFrameSize(cameraFeed_->source(), scene.camera, args_.scene);
    if (!args_.lightCamera.empty()) {
        lightCamera_.emplace(args_.scene, args_.overrides, args_.lightSmoothingSeconds);
        lightFeed_.emplace(openFrameSource(args_.lightCamera, args_.patternFps), true);
    }
}

void Server::stopWithError(std::exception_ptr error) {
    std::lock_guard lock(sessionMutex_);
    if (!feedError_) feedError_ = error;
    stop_ = true;
    changed_.notify_all();
}

// Takes `feed`'s frames until the server stops or the source ends (said once on stderr, with `ended`'s text);
// `use` takes each. A source that fails stops the server with its error.
template <typename Use>
void Server::readFeed(FrameFeed& feed, const char* ended, Use use) {
    constexpr auto kPoll = std::chrono::milliseconds(100);
    int64_t frames = 0;
    try {
        while (!stopReading_) {
            std::optional<FrameFeed::Arrival> arrival = feed.takeUntil(Clock::now() + kPoll);
            if (!arrival) {
                if (!feed.ended()) continue;
                note("deltagi: {}: ended after {} frames; the session goes on {}\n", feed.source().name(),
                     frames, ended);
                return;
            }
            ++frames;
            use(*arrival);
        }
    } catch (...) {
        stopWithError(std::current_exception());
    }
}

// Each frame of the server's camera goes where a page's would; one that a newer replaces before the render
// thread took it is dropped. Files are replayed at their timestamps' pace, as a camera would give them.
void Server::readCamera() {
    readFeed(*cameraFeed_, "over the last", [&](FrameFeed::Arrival& arrival) {
        CameraInput input;
        input.image = std::move(arrival.frame.image);
        input.arrived = arrival.arrived;
        input.timeSeconds = arrival.frame.timeSeconds;
        input.number = arrival.frame.index + 1;
        std::lock_guard lock(sessionMutex_);
        cameraDropped_ += arrival.dropped + (cameraInput_ ? 1 : 0);
        cameraInput_ = std::move(input);
        changed_.notify_all();
    });
}

// Each light-camera frame, averaged with those before it, becomes the environment of the next frame.
void Server::readLight() {
    readFeed(*lightFeed_, "in its last light", [&](FrameFeed::Arrival& arrival) {
        const Clock::time_point start = Clock::now();
        auto environment = std::make_shared<const Environment>(lightCamera_->environment(
            std::move(arrival.frame.image), arrival.frame.timeSeconds, lightFeed_->source().name()));
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
        std::lock_guard lock(sessionMutex_);
        pendingEnvironment_ = std::move(environment);
        ++lightFrames_;
        environmentMs_ = ms;
        changed_.notify_all();
    });
}

void Server::handleMessages() {
    for (;;) {
        Incoming message;
        {
            std::unique_lock lock(inboxMutex_);
            inboxWake_.wait(lock, [&] { return stopHandler_ || !inbox_.empty(); });
            if (stopHandler_) return;
            message = std::move(inbox_.front());
            inbox_.pop_front();
        }
        live::MessageResult result;
        {
            std::lock_guard lock(sessionMutex_);
            result = session_.handle(message.text, message.client->id());
            if (result.changed) changed_.notify_all();
        }
        if (!result.reply.is_null()) message.client->reply(live::jsonText(result.reply));
        if (result.changed) publishState();
    }
}

void Server::onClose(const std::shared_ptr<WebSocket>& socket) {
    std::lock_guard lock(clientsMutex_);
    clients_.erase(socket.get());
}

void Server::publishState() {
    std::shared_ptr<const std::string> state;
    {
        std::lock_guard lock(sessionMutex_);
        state = std::make_shared<const std::string>(live::jsonText(session_.state()));
    }
    std::lock_guard lock(clientsMutex_);
    for (auto& [connection, client] : clients_) client->state(state);
}

int Server::run() {
    for (const std::string& warning : session_.scene().warnings)
        fmt::print(stderr, "deltagi: warning: {}\n", warning);
    openFeeds();
    if (!isLoopback(args_.host))
        fmt::print(stderr,
                   "deltagi: warning: listening on {}: anyone who can reach this machine there can watch and "
                   "change the session (the default, 127.0.0.1, is this machine only)\n",
                   args_.host);
    WebServer::Handlers handlers;
    handlers.request = [this](const HttpRequest& request) { return onRequest(request); };
    handlers.acceptWebSocket = [this](const HttpRequest& request) { return acceptWebSocket(request); };
    handlers.open = [this](const std::shared_ptr<WebSocket>& socket) { return onOpen(socket); };
    handlers.message = [this](const std::shared_ptr<WebSocket>& socket, bool binary, std::string_view data) {
        onMessage(socket, binary, data);
    };
    handlers.close = [this](const std::shared_ptr<WebSocket>& socket) { onClose(socket); };
    WebServer::Limits limits;
    limits.maxMessageBytes = kMaxCameraFrameBytes;
    WebServer web(args_.host, args_.port, limits, std::move(handlers));
    port_ = web.port();
    std::thread handler([this] { handleMessages(); });
    std::thread renderer([this] { renderLoop(); });
    if (cameraFeed_) cameraReader_ = std::thread([this] { readCamera(); });
    if (lightFeed_) lightReader_ = std::thread([this] { readLight(); });
    const std::string shown = args_.host.find(':') != std::string::npos ? "[" + args_.host + "]" : args_.host;
    fmt::print("deltagi serve: http://{}:{}/ ({}; Ctrl-C stops)\n", shown, port_, args_.scene.string());
    std::fflush(stdout);
    // Runs until SIGINT or SIGTERM ends the process (cli/outputs.cpp), or a source of live --serve fails.
    renderer.join();
    stopReading_ = true;
    for (std::thread* reader : {&cameraReader_, &lightReader_})
        if (reader->joinable()) reader->join();
    {
        std::lock_guard lock(inboxMutex_);
        stopHandler_ = true;
        inboxWake_.notify_all();
    }
    handler.join();
    web.stop();
    if (feedError_) std::rethrow_exception(feedError_);
    return 0;
}

}  // namespace serve

CLI::App* addServeCommand(CLI::App& app, ServeArgs& args, int maxThreads) {
    CLI::App* command = app.add_subcommand(
        "serve", "A live session in the browser: drag the virtual objects over the real scene (README)");
    command->add_option("scene", args.scene, "Scene file (JSON, see docs/scene-format.md)")->required();
    command->add_option("--port", args.port, "TCP port (default 8080; 0: any free port, printed)")
        ->check(CLI::Range(0, 65535));
    command->add_option(
        "--host", args.host,
        "Address to listen on (default 127.0.0.1: this machine only; say 0.0.0.0 to let others "
        "in, with a warning)");
    command->add_option(
        "--allow-host", args.allowedHosts,
        "A host name the page may be opened by, besides this machine's addresses and localhost "
        "(repeatable; requests naming others are refused)");
    command->add_option("--set", args.overrides, "Override a scene key: KEY=VALUE (repeatable)");
    command->add_option("--threads", args.threads, "Worker threads (default: all cores)")
        ->check(CLI::Range(1, maxThreads));
    command->add_option("--jpeg-quality", args.jpegQuality, "Quality of the streamed frames (default 85)")
        ->check(CLI::Range(1, 100));
    command
        ->add_option("--interactive-scale", args.interactiveScale,
                     "While something changes, render at 1/N of the width and height (default 2; 1: full "
                     "size); the idle frame is always full size")
        ->check(CLI::IsMember({1, 2, 4}));
    return command;
}

int runServe(const ServeArgs& args) {
    std::optional<tbb::global_control> threadLimit;
    if (args.threads > 0) threadLimit.emplace(tbb::global_control::max_allowed_parallelism, args.threads);
    serve::Server server(args);
    return server.run();
}

}  // namespace deltagi::cli
