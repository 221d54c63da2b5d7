// `deltagi serve`'s render thread (serve_server.h): it registers the camera frames that come, renders the
// session's frames and hands them to the clients.
#include "serve_server.h"

namespace deltagi::cli::serve {

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
            {"queued_ms",  // from its arrival until the render thread took it
             std::round(std::chrono::duration<double, std::milli>(start - input.arrived).count() * 100.0) /
                 100.0},
            {"decode_ms",
             std::round(std::chrono::duration<double, std::milli>(decoded - start).count() * 100.0) / 100.0},
            {"track_ms", std::round(trackMs * 100.0) / 100.0}};
    if (tracked.uncertain) info["uncertain"] = true;
    if (tracked.state == TrackedFrame::State::Registered)
        info["reprojection_error_px"] = std::round(tracked.reprojectionErrorPx * 1e4) / 1e4;
    if (tracked.state != TrackedFrame::State::Lost) {  // where the camera is, smoothed (world units)
        const glm::vec3 p(tracked.worldFromCamera[3]);
        info["position"] = {std::round(p.x * 1e5) / 1e5, std::round(p.y * 1e5) / 1e5,
                            std::round(p.z * 1e5) / 1e5};
    }
    return true;
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
    json lightInfo;  // the light camera's newest frame, said with every frame once there is one
    for (;;) {
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
            // An interactive frame with temporal reuse averages the frames before it, and one with "auto"
            // refine_budget or object_gather_rays spends a frame's time, not a still's: it is not render()'s
            // image even with the scene's own options, so the idle refinement renders that one.
            sameOptions = scale == 1 && optionsToJson(wanted) == optionsToJson(own) &&
                          own.render.temporalFrames <= 1 && own.render.refineBudget >= 0.0f &&
                          own.diffuse.objectGatherRays >= 0;
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
            // The refined frame is the still `deltagi render` gives: nothing of the frames before it is
            // averaged in, and the options' "auto" is a single render's.
            std::optional<RenderOutput> rendered;
            if (!unregistered)
                rendered = refining ? fullFrames.renderStill(full) : interactiveFrames.render(interactive);
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

}  // namespace deltagi::cli::serve
