// `deltagi serve`: the web server's handlers, the render thread and what each client has waiting
// (serve_command.h).
//
// Threads: the web server's two (web_server.h) answer HTTP requests, read each WebSocket's messages and write
// to each what its Client has waiting; a handler thread passes the messages to the session under
// `sessionMutex_`; one render thread owns the renderers and their scenes, copies the session's scene when it
// changed, renders, encodes the view as a JPEG and hands it to every client (a frame not yet sent when a
// newer one comes is dropped: no queue grows when a browser is slower than the renderer).
//
// A page may send the frames of the user's camera (getUserMedia) as binary messages, JPEGs of the scene
// camera's size: the newest waits for the render thread (one that a newer replaces is dropped, and counted),
// which registers it by the scene's markers and renders the objects over it from the registered pose.
#include "serve_command.h"

#include <arpa/inet.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <fmt/core.h>
#include <tbb/global_control.h>
#include <nlohmann/json.hpp>

#include "deltagi/environment.h"
#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "live/frame_source.h"
#include "live/light_camera.h"
#include "live/live_session.h"
#include "live/marker_registration.h"
#include "messages.h"
#include "track_command.h"
#include "web_assets.h"
#include "web_server.h"

namespace deltagi::cli {
namespace {

using Clock = std::chrono::steady_clock;
using live::Session;
using live::View;
using nlohmann::json;

// A frame after the last change waits this long before the idle refinement starts, so that a pause between
// two mouse moves does not start a full-quality frame that the next move has to wait for.
constexpr auto kRefineDelay = std::chrono::milliseconds(150);
constexpr size_t kMaxClients = 32;
constexpr size_t kMaxQueuedReplies = 32;
constexpr size_t kMaxWaitingMessages = 256;
// A camera frame's JPEG: 8 MiB is far above what a browser encodes for 4096 x 4096 at quality 0.9.
constexpr size_t kMaxCameraFrameBytes = 8 * 1024 * 1024;

struct Frame {
    uint64_t number = 0;
    std::string info;  // JSON text, sent before the picture
    std::string jpeg;
};

// One page's socket: what is to be sent to it waits here, and the socket takes it (next()) whenever it has
// written the previous message. Replies queue (the oldest are dropped beyond kMaxQueuedReplies); of the
// states and the frames only the newest waits: a frame not yet sent when a newer one comes is dropped, and no
// queue grows when a browser is slower than the renderer.
class Client {
  public:
    Client(std::weak_ptr<WebSocket> socket, int id) : socket_(std::move(socket)), id_(id) {}
    int id() const { return id_; }
    // The camera frames this client sent (numbered from 1); one socket's messages come one at a time.
    int64_t cameraFrames = 0;

    void reply(std::string text) {
        {
            std::lock_guard lock(mutex_);
            if (replies_.size() >= kMaxQueuedReplies) replies_.pop_front();
            replies_.push_back(std::make_shared<const std::string>(std::move(text)));
        }
        wake();
    }
    void state(std::shared_ptr<const std::string> state) {
        {
            std::lock_guard lock(mutex_);
            state_ = std::move(state);
        }
        wake();
    }
    void frame(std::shared_ptr<const Frame> frame) {
        {
            std::lock_guard lock(mutex_);
            frame_ = std::move(frame);
        }
        wake();
    }
    // The next message to write: the replies, the state, then the frame's info and its picture.
    std::optional<WebSocketMessage> next() {
        std::lock_guard lock(mutex_);
        if (picture_) return WebSocketMessage{true, std::exchange(picture_, nullptr)};
        if (!replies_.empty()) {
            WebSocketMessage message{false, std::move(replies_.front())};
            replies_.pop_front();
            return message;
        }
        if (state_) return WebSocketMessage{false, std::exchange(state_, nullptr)};
        if (frame_ && frame_->number != sent_) {
            sent_ = frame_->number;
            picture_ = std::shared_ptr<const std::string>(frame_, &frame_->jpeg);
            return WebSocketMessage{false, std::shared_ptr<const std::string>(frame_, &frame_->info)};
        }
        return std::nullopt;
    }

  private:
    void wake() {
        if (std::shared_ptr<WebSocket> socket = socket_.lock()) socket->wake();
    }

    std::weak_ptr<WebSocket> socket_;
    int id_;
    std::mutex mutex_;
    std::deque<std::shared_ptr<const std::string>> replies_;
    std::shared_ptr<const std::string> state_;
    std::shared_ptr<const Frame> frame_;
    std::shared_ptr<const std::string> picture_;  // the picture of the frame whose info went last
    uint64_t sent_ = 0;
};

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

// A scene-camera frame waiting for the render thread.
struct CameraInput {
    std::string jpeg;            // from a page
    std::optional<Image> image;  // from the server's own camera (live --serve), decoded
    Clock::time_point arrived;
    double timeSeconds = 0.0;  // for the pose filter: the source's timestamp, or the arrival
    std::weak_ptr<Client> client;
    int clientId = 0;    // 0: the server's own camera
    int64_t number = 0;  // the client's count, or the source's frame number + 1
};

// The newest registered camera frame, which the frames are rendered over until the next.
struct LiveCamera {
    glm::mat4 worldFromCamera{1.0f};
    Image image;    // the camera's size
    Image reduced;  // at 1 / reducedScale of it, for the interactive frames
    int reducedScale = 1;
    std::optional<glm::vec3> viewpoint;  // the first registered camera's position (cli/live_command.cpp)
};

class Server {
  public:
    Server(const ServeArgs& args) : args_(args), session_(args.scene, args.overrides) {
        const Scene& scene = session_.scene();
        if (!scene.markers.empty()) tracker_.emplace(scene.markers, scene.camera, args.tracking);
        cameraSize_ = {scene.camera.width, scene.camera.height};
    }

    int run();

  private:
    // The web server's handlers (web_server.h).
    HttpResponse onRequest(const HttpRequest& request);
    bool acceptWebSocket(const HttpRequest& request);
    std::function<std::optional<WebSocketMessage>()> onOpen(const std::shared_ptr<WebSocket>& socket);
    void onMessage(const std::shared_ptr<WebSocket>& socket, bool binary, std::string_view data);
    void onClose(const std::shared_ptr<WebSocket>& socket);

    void onCameraFrame(const std::shared_ptr<Client>& client, std::string_view data);
    // Decodes and registers a camera frame; false (the client told why) when it cannot be.
    bool registerFrame(const CameraInput& input, int64_t dropped, TrackedFrame& tracked, Image& image,
                       json& info);
    void renderLoop();
    void handleMessages();
    // `live --serve`: open the sources (InputError before the server starts), then read them on threads of
    // their own into cameraInput_ and pendingEnvironment_.
    void openFeeds();
    void readCamera();
    void readLight();
    template <typename Use>
    void readFeed(FrameFeed& feed, const char* ended, Use use);
    void stopWithError(std::exception_ptr error);
    void publishState();
    bool hostAllowed(const HttpRequest& request) const;

    ServeArgs args_;
    std::mutex sessionMutex_;  // the session and the fields below it
    std::condition_variable changed_;
    Session session_;
    bool stop_ = false;
    std::shared_ptr<const Frame> latestFrame_;
    std::shared_ptr<const Image> latestComposite_;
    bool latestRefined_ = false;
    std::optional<CameraInput> cameraInput_;  // the newest camera frame not yet taken by the render thread
    int64_t cameraDropped_ = 0;               // camera frames replaced by a newer one before being taken
    std::shared_ptr<const Environment> pendingEnvironment_;  // the light camera's newest, not yet taken
    int64_t lightFrames_ = 0;
    double environmentMs_ = 0.0;    // the newest light frame's averaging and light extraction
    std::exception_ptr feedError_;  // a source that failed: the server stops and reports it

    // The server's own sources (live --serve) and their readers.
    std::optional<FrameFeed> cameraFeed_, lightFeed_;
    std::optional<LightCamera> lightCamera_;
    std::thread cameraReader_, lightReader_;
    std::atomic<bool> stopReading_{false};

    // The render thread's own.
    std::optional<MarkerTracker> tracker_;  // when the scene places markers
    std::pair<int, int> cameraSize_;
    const Clock::time_point started_ = Clock::now();

    // Messages wait here for the handler thread, which parses and checks them: the web server's threads only
    // move bytes.
    struct Incoming {
        std::shared_ptr<Client> client;
        std::string text;
    };
    std::mutex inboxMutex_;
    std::condition_variable inboxWake_;
    std::deque<Incoming> inbox_;
    bool stopHandler_ = false;

    std::mutex clientsMutex_;
    std::map<const WebSocket*, std::shared_ptr<Client>> clients_;
    int nextClient_ = 1;
    int port_ = 0;
};

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

const char* contentType(const std::string& name) {
    if (name.ends_with(".html")) return "text/html; charset=utf-8";
    if (name.ends_with(".js")) return "text/javascript; charset=utf-8";
    if (name.ends_with(".css")) return "text/css; charset=utf-8";
    return "application/octet-stream";
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

void Server::onCameraFrame(const std::shared_ptr<Client>& client, std::string_view data) {
    const int64_t number = ++client->cameraFrames;
    CameraInput input;
    input.jpeg.assign(data);
    input.arrived = Clock::now();
    input.timeSeconds = std::chrono::duration<double>(input.arrived - started_).count();
    input.client = client;
    input.clientId = client->id();
    input.number = number;
    std::lock_guard lock(sessionMutex_);
    if (cameraInput_) ++cameraDropped_;
    cameraInput_ = std::move(input);
    changed_.notify_all();
}

bool Server::registerFrame(const CameraInput& input, int64_t dropped, TrackedFrame& tracked, Image& image,
                           json& info) {
    const auto fail = [&](const std::string& message) {
        if (std::shared_ptr<Client> client = input.client.lock())
            client->reply(live::jsonText(json{
                {"type", "error"}, {"message", fmt::format("camera frame {}: {}", input.number, message)}}));
        return false;
    };
    if (!tracker_)
        return fail(
            fmt::format("{}: markers: the scene places no marker to register the camera by "
                        "(docs/scene-format.md, \"markers\")",
                        args_.scene.string()));
    const Clock::time_point start = Clock::now();
    if (input.image) {
        image = *input.image;
    } else {
        try {
            image = live::decodeCameraFrame(input.jpeg, cameraSize_.first, cameraSize_.second);
        } catch (const InputError& e) {
            return fail(e.message());
        }
    }
    const Clock::time_point decoded = Clock::now();
    tracked = tracker_->track(image, input.timeSeconds);
    const double trackMs = std::chrono::duration<double, std::milli>(Clock::now() - decoded).count();
    const char* state = tracked.state == TrackedFrame::State::Registered ? "markers"
                        : tracked.state == TrackedFrame::State::Held     ? "held"
                                                                         : "lost";
    info = {{"client", input.clientId},
            {"number", input.number},
            {"dropped", dropped},
            {"registration", state},
            {"markers_seen", tracked.markersSeen},
            {"decode_ms",
             std::round(std::chrono::duration<double, std::milli>(decoded - start).count() * 100.0) / 100.0},
            {"track_ms", std::round(trackMs * 100.0) / 100.0}};
    if (tracked.state == TrackedFrame::State::Registered)
        info["reprojection_error_px"] = std::round(tracked.reprojectionErrorPx * 1e4) / 1e4;
    if (tracked.state != TrackedFrame::State::Lost) {  // where the camera is, smoothed (world units)
        const glm::vec3 p(tracked.worldFromCamera[3]);
        info["position"] = {std::round(p.x * 1e5) / 1e5, std::round(p.y * 1e5) / 1e5,
                            std::round(p.z * 1e5) / 1e5};
    }
    return true;
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

// Interactive frames while the scene changes; once it has not changed for kRefineDelay, one frame with the
// scene's own options (the image `deltagi render` gives), then nothing until the next change.
void Server::renderLoop() {
    Scene interactive, full;
    FrameRenderer interactiveFrames, fullFrames;
    uint64_t interactiveVersion = 0, interactiveStructure = 0, fullStructure = 0;
    bool refined = true;  // nothing to refine before the first frame
    Clock::time_point lastChange = Clock::now();
    uint64_t frameNumber = 0;
    bool layers = false;
    std::optional<LiveCamera> camera;                // the last registered camera frame, once a page sent one
    std::shared_ptr<const Environment> environment;  // the light camera's newest (live --serve)
    bool interactiveLit = false, fullLit = false;    // whether the two scenes have it
    for (;;) {
        json lightInfo;
        bool refining = false, sameOptions = false;
        int scale = 1;  // the interactive frames at 1 / scale of the camera's width and height
        View view;
        int client = 0;
        int64_t seq = 0;
        uint64_t version = 0;
        std::optional<CameraInput> cameraInput;
        int64_t cameraDropped = 0;
        {
            std::unique_lock lock(sessionMutex_);
            for (;;) {
                if (stop_) return;
                if (session_.version() != interactiveVersion || cameraInput_ || pendingEnvironment_) break;
                if (!refined) {
                    if (Clock::now() >= lastChange + kRefineDelay) break;
                    changed_.wait_until(lock, lastChange + kRefineDelay);
                    continue;
                }
                changed_.wait(lock);
            }
            cameraInput.swap(cameraInput_);
            cameraDropped = cameraDropped_;
            const bool newLight = pendingEnvironment_ != nullptr;
            if (newLight) {
                environment = std::move(pendingEnvironment_);
                pendingEnvironment_.reset();
                interactiveLit = fullLit = false;
                lightInfo = {{"frames", lightFrames_},
                             {"environment_ms", std::round(environmentMs_ * 100.0) / 100.0}};
            }
            const Scene& scene = session_.scene();
            view = session_.view();
            layers = live::viewNeedsLayers(view);
            client = session_.lastInputClient();
            seq = session_.lastInputSeq();
            version = session_.version();
            scale = live::canReduceResolution(scene.camera.width, scene.camera.height, args_.interactiveScale)
                        ? args_.interactiveScale
                        : 1;
            Options wanted = live::interactiveOptions(scene.options, scene.camera.width, scene.camera.height,
                                                      scene.lights.size(), scale);
            wanted.render.layers = layers;
            Options own = scene.options;
            own.render.layers = layers;
            // An interactive frame with temporal reuse averages the frames before it: it is not render()'s
            // image even with the scene's own options, so the idle refinement renders that one.
            sameOptions =
                scale == 1 && optionsToJson(wanted) == optionsToJson(own) && own.render.temporalFrames <= 1;
            if (session_.version() != interactiveVersion || cameraInput || newLight) {
                if (session_.structureVersion() != interactiveStructure || interactiveVersion == 0) {
                    live::interactiveScene(scene, wanted, scale, interactive);
                    interactiveStructure = session_.structureVersion();
                    interactiveLit = false;
                } else {
                    interactive.virtuals = scene.virtuals;
                }
                interactiveVersion = session_.version();
                lastChange = Clock::now();
                refined = sameOptions;
            } else {
                refining = true;
                if (session_.structureVersion() != fullStructure || fullStructure == 0) {
                    full = scene;
                    full.options = own;
                    fullStructure = session_.structureVersion();
                    fullLit = false;
                } else {
                    full.virtuals = scene.virtuals;
                }
            }
        }
        // A camera frame: registered, then rendered over (when the markers give a pose) or shown as it is.
        json cameraInfo;
        std::optional<Image> unregistered;
        if (cameraInput) {
            TrackedFrame tracked;
            Image image;
            if (!registerFrame(*cameraInput, cameraDropped, tracked, image, cameraInfo)) {
                cameraInput.reset();  // the frame is rendered as if it had not come
            } else if (tracked.state == TrackedFrame::State::Lost) {
                unregistered = std::move(image);
                refined = true;  // nothing to refine: the camera image is the frame
            } else {
                if (!camera) camera.emplace();
                camera->worldFromCamera = tracked.worldFromCamera;
                camera->image = std::move(image);
                camera->reducedScale = 0;
                if (!camera->viewpoint) camera->viewpoint = glm::vec3(tracked.worldFromCamera[3]);
                std::lock_guard lock(sessionMutex_);
                session_.setCameraPose(tracked.worldFromCamera);  // drags pick as this camera sees
            }
        }
        // The light camera's environment, in the scene about to be rendered.
        if (environment && !unregistered) {
            bool& lit = refining ? fullLit : interactiveLit;
            if (!lit) setEnvironment(refining ? full : interactive, *environment);
            lit = true;
        }
        // The frames are rendered from the registered camera, over its image.
        if (camera && !unregistered) {
            Scene& target = refining ? full : interactive;
            const int targetScale = refining ? 1 : scale;
            target.camera.worldFromCamera = camera->worldFromCamera;
            target.options.volume.viewpoint = camera->viewpoint;
            if (targetScale == 1) {
                target.background = camera->image;
            } else {
                if (camera->reducedScale != targetScale) {
                    camera->reduced = live::reducedImage(camera->image, targetScale);
                    camera->reducedScale = targetScale;
                }
                target.background = camera->reduced;
            }
        }
        try {
            // The refined frame is a still: nothing of the frames before it is averaged in.
            if (refining) fullFrames.clearHistory();
            std::optional<RenderOutput> rendered;
            if (!unregistered)
                rendered = refining ? fullFrames.render(full) : interactiveFrames.render(interactive);
            const auto encodeStart = Clock::now();
            auto frame = std::make_shared<Frame>();
            frame->number = ++frameNumber;
            const Image& picture = rendered ? rendered->composite : *unregistered;
            frame->jpeg =
                live::encodeJpeg(rendered ? live::viewPixels(*rendered, view) : encodeSrgb8(picture),
                                 picture.width(), picture.height(), args_.jpegQuality);
            const double encodeMs =
                std::chrono::duration<double, std::milli>(Clock::now() - encodeStart).count();
            json info = {{"type", "frame"},
                         {"number", frame->number},
                         {"version", version},
                         {"view", unregistered ? "camera" : live::viewName(view)},
                         {"refined", !unregistered && (refining || sameOptions)},
                         {"scale", refining || unregistered ? 1 : scale},
                         {"client", client},
                         {"seq", seq},
                         {"timings", rendered ? live::timingsJson(*rendered)
                                              : json{{"stages", json::array()}, {"total_ms", 0.0}}},
                         {"encode_ms", std::round(encodeMs * 100.0) / 100.0},
                         {"bytes", frame->jpeg.size()}};
            if (cameraInput) {
                cameraInfo["latency_ms"] =
                    std::round(std::chrono::duration<double, std::milli>(Clock::now() - cameraInput->arrived)
                                   .count() *
                               100.0) /
                    100.0;
                info["camera"] = cameraInfo;
            }
            if (!lightInfo.is_null()) info["light"] = lightInfo;
            frame->info = live::jsonText(info);
            auto composite = std::make_shared<const Image>(rendered ? std::move(rendered->composite)
                                                                    : std::move(*unregistered));
            {
                std::lock_guard lock(sessionMutex_);
                latestFrame_ = frame;
                latestComposite_ = std::move(composite);
                latestRefined_ = (refining || sameOptions) && session_.version() == version;
            }
            std::lock_guard lock(clientsMutex_);
            for (auto& [connection, c] : clients_) c->frame(frame);
        } catch (const std::exception& e) {
            // A frame that cannot be rendered (the memory for the volumes, a bad state): every client is
            // told, and the session waits for the next change.
            const std::string text =
                live::jsonText(json{{"type", "error"}, {"message", fmt::format("frame: {}", e.what())}});
            interactiveFrames.clear();
            fullFrames.clear();
            std::lock_guard lock(clientsMutex_);
            for (auto& [connection, c] : clients_) c->reply(text);
        }
        if (refining) refined = true;
    }
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

}  // namespace

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
    Server server(args);
    return server.run();
}

}  // namespace deltagi::cli
