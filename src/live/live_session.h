// The state of a live session (`deltagi serve`, cli/serve_server.h) and the handler of its clients'
// messages, kept apart from the web server so that it can be tested and fuzzed without sockets.
//
// A session holds the scene document (the scene file's JSON, with the command line's overrides) and the Scene
// loaded from it. Every change a message makes is made to both, so that the document, saved and rendered by
// `deltagi render`, gives the session's picture: an object's new place is written as its 4x4 "transform", a
// light's as its "position" and "intensity", an option under "options". Messages are JSON objects with a
// "type"; anything else (malformed JSON, an unknown type or key, NaN, an unknown object, an option out of
// range) is refused with an error reply and changes nothing.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "deltagi/renderer.h"
#include "deltagi/scene.h"

namespace deltagi {

class RayScene;

namespace live {

// What the page shows: the composite, the photo (or the real scene rendered), 0.5 + 4 x delta, the object
// mask, and the compositing layers (object, 0.5 + 4 x shadow, 0.5 + 4 x indirect, depth).
enum class View { Composite, Background, Delta, Mask, Object, Shadow, Indirect, Depth };
std::optional<View> parseView(std::string_view name);
std::string_view viewName(View view);
// Whether the view needs RenderOutput's layers (options.render.layers).
bool viewNeedsLayers(View view);

// Bounds on what a client may ask for.
inline constexpr size_t kMaxMessageBytes = 16 * 1024;
inline constexpr int kMaxLiveVolumeResolution = 256;
inline constexpr float kMaxCoordinate = 1e4f;  // light positions, in world units, per axis
inline constexpr float kMaxRotationDeg = 360.0f;

// The result of one message.
struct MessageResult {
    // To the sender only: {"type":"error","message":...}, {"type":"pong"}, or {"type":"ok"} for a message
    // that changed nothing (the view it shows already); null after a change.
    nlohmann::json reply;
    bool changed = false;  // the scene or the view changed: render again and send every client the state
};

class Session {
  public:
    // Loads `file` with the command line's `overrides` (InputError for a bad scene, as `deltagi render`
    // would; a scene with a "sequence" too, whose frames a live session does not play).
    Session(const std::filesystem::path& file, const std::vector<std::string>& overrides);
    ~Session();
    Session(const Session&) = delete;
    Session& operator=(const Session&) = delete;

    // One message from client `client` (any number that names the connection in frame infos).
    MessageResult handle(std::string_view message, int client = 0);

    // Every client's view of the session: objects (name, anchor pixel), lights, the options the page
    // controls, the view, the selection.
    nlohmann::json state() const;
    // The scene document as it is now, with relative file paths made absolute (so that it renders from
    // wherever it is saved).
    nlohmann::json document() const;

    // The pose of the registered scene camera (a live camera's frames, cli/serve_render.cpp): drags pick the
    // surface under the cursor as this camera sees it, and the state's anchors are its pixels. Not a change
    // (no version): the document keeps the file's camera.
    void setCameraPose(const glm::mat4& worldFromCamera);

    // The scene, with the objects at the places the messages gave them (a drag only records the place; the
    // meshes are moved here, once for any number of drags between two frames).
    const Scene& scene();
    View view() const { return view_; }
    // Incremented by every change; `structure` by changes other than objects' transforms and the view
    // (lights, options), after which a renderer copies the whole scene rather than the objects.
    uint64_t version() const { return version_; }
    uint64_t structureVersion() const { return structureVersion_; }
    // The last input that changed something: its client and its "seq" (0 when it had none).
    int lastInputClient() const { return lastClient_; }
    int64_t lastInputSeq() const { return lastSeq_; }

  private:
    MessageResult dispatch(const nlohmann::json& message);
    void drag(const nlohmann::json& message);
    void rotate(const nlohmann::json& message);
    void light(const nlohmann::json& message);
    void options(const nlohmann::json& message);
    int objectIndex(const nlohmann::json& message) const;
    void placeObject(int object, const glm::mat4& worldFromObject);
    void applyPlacements();
    Bounds3f meshBounds(int object) const;

    std::filesystem::path file_;
    nlohmann::json document_;
    std::unique_ptr<Scene> scene_;          // in place: picking_ points into its real meshes
    std::unique_ptr<RayScene> picking_;     // the real scene, for the surface under the cursor
    std::vector<std::vector<int>> meshes_;  // per "virtual" entry, its meshes in scene_->virtuals
    std::vector<std::string> names_;        // per entry
    // Per entry: its transform, its meshes' bounds there (moved with it by drags, computed again after a
    // rotation), and whether its meshes are still to be moved there (applyPlacements).
    std::vector<glm::mat4> transforms_;
    std::vector<Bounds3f> bounds_;
    std::vector<bool> unplaced_;
    // Per entry: where it rests on the real surfaces (world) and that surface's normal.
    std::vector<glm::vec3> contact_, contactNormal_;
    Bounds3f realBounds_;
    size_t fileLights_ = 0;  // the scene file's lights (the environment's follow them)
    int selected_ = 0;
    View view_ = View::Composite;
    uint64_t version_ = 1, structureVersion_ = 1;
    int lastClient_ = 0;
    int64_t lastSeq_ = 0;
};

// The options of the frames rendered while the scene changes, for a width x height image and `lightCount`
// lights (the scene's and its environment's): the scene's own, with one G-buffer sample per pixel, the cones
// and the shadow rays at twice their pixel strides (at most 32), reflective shadow maps of half the side (of
// a single light, when "auto") and at most 4 rays for the objects' further bounce. On the benchmark scene
// each of these about halves a stage: G-buffer, diffuse cones, shadows, RSM update and injection, the
// objects' bounce. The idle frames use the scene's own options, which give `deltagi render`'s image.
//
// `scale` > 1: the interactive frames are rendered at 1 / scale of the width and height (interactiveScene);
// the pixel strides, resolved for the full image as above, are divided by `scale` (at least 1), so that the
// cones and shadow rays stay as dense on the surfaces as in full-size interactive frames.
Options interactiveOptions(const Options& full, int width, int height, size_t lightCount, int scale = 1);

// Whether a width x height camera can be rendered at 1 / scale of its size: both divisible by `scale`, and at
// least 64 x 48 pixels after it.
bool canReduceResolution(int width, int height, int scale);

// The scene of the interactive frames: `scene` with `options`, its camera and photo reduced to 1 / scale of
// their width and height (the photo averaged over scale x scale blocks) where canReduceResolution allows;
// returns the scale used (1 or `scale`).
int interactiveScene(const Scene& scene, const Options& options, int scale, Scene& out);

// `image` averaged over scale x scale blocks (its width and height divided by `scale`, rounded down); a copy
// for `scale` 1.
Image reducedImage(const Image& image, int scale);

// A scene-camera frame sent by the page (a JPEG of the camera's width x height, 8-bit sRGB, RGB or grey) as a
// linear RGB image. The header's size is checked before the pixels are decoded; InputError ("camera frame")
// for bytes that are not a JPEG of that size.
Image decodeCameraFrame(std::string_view jpeg, int width, int height);

// The picture of `view`, as 8-bit sRGB RGB pixels (width x height x 3), for the page.
std::vector<uint8_t> viewPixels(const RenderOutput& output, View view);
// JPEG (quality 1-100) of 8-bit RGB pixels, and a PNG of a linear image as `deltagi render -o X.png` writes
// it (8-bit sRGB), in memory. Throw InputError when the encoder fails.
std::string encodeJpeg(const std::vector<uint8_t>& rgb, int width, int height, int quality);
std::string encodePng(const Image& image);

// JSON text of `value` for a client or a download (`indent` as json::dump's): bytes of a string that are not
// UTF-8 (a message's own bytes quoted back in an error, a cut character, a file name) become U+FFFD rather
// than throw.
std::string jsonText(const nlohmann::json& value, int indent = -1);

// The frame's stage timings as JSON: {"stages": [[name, ms], ...], "total_ms": ms}.
nlohmann::json timingsJson(const RenderOutput& output);

}  // namespace live
}  // namespace deltagi
