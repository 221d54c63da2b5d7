// `deltagi serve`'s session server (serve_command.h), shared by its two files: serve_command.cpp (the web
// server's handlers, the sources of `live --serve`, the message handler and the command) and
// serve_render.cpp (the render thread).
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
#pragma once

#include "serve_command.h"

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
#include "web_server.h"

namespace deltagi::cli::serve {

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
    // The server's seconds minus the page's at its first camera frame that said when it was taken: the
    // page's capture times on the server's clock.
    std::optional<double> cameraClockOffset;

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

}  // namespace deltagi::cli::serve
