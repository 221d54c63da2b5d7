// The live session's state and message handler (live_session.h).
#include "live/live_session.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <utility>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "core/ray_scene.h"
#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "deltagi/transforms.h"
#include "io/image_codecs.h"
#include "io/image_encode.h"
#include "scene/json_reader.h"
#include "scene/option_table.h"

namespace deltagi::live {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr std::array<std::pair<View, std::string_view>, 8> kViews = {{{View::Composite, "composite"},
                                                                      {View::Background, "background"},
                                                                      {View::Delta, "delta"},
                                                                      {View::Mask, "mask"},
                                                                      {View::Object, "object"},
                                                                      {View::Shadow, "shadow"},
                                                                      {View::Indirect, "indirect"},
                                                                      {View::Depth, "depth"}}};

// The options a client may change, by their dotted path under "options".
constexpr std::array<std::string_view, 9> kLiveOptions = {"volume.resolution",
                                                          "diffuse.count",
                                                          "diffuse.pixel_stride",
                                                          "diffuse.relight_pixel_stride",
                                                          "specular.relight_pixel_stride",
                                                          "shadow.pixel_stride",
                                                          "shadow.relight_pixel_stride",
                                                          "shadow.ray_samples",
                                                          "render.samples_per_pixel"};

[[noreturn]] void refuse(const std::string& where, const std::string& what) {
    throw InputError(where, what);
}

// Fails at the first key of `message` not in `allowed` ("type" and "seq" are always allowed).
void allowKeys(const json& message, std::initializer_list<std::string_view> allowed) {
    for (const auto& [key, value] : message.items()) {
        if (key == "type" || key == "seq") continue;
        if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
            refuse(message.value("type", std::string()),
                   fmt::format("unknown key \"{}\"", key.size() > 64 ? key.substr(0, 64) + "..." : key));
    }
}

double number(const json& message, const char* key, double lo, double hi) {
    const std::string where = fmt::format("{}.{}", message.value("type", std::string()), key);
    if (!message.contains(key)) refuse(where, "missing");
    const json& v = message.at(key);
    if (!v.is_number()) refuse(where, "expected a number, got " + describeValue(v));
    const double d = v.get<double>();
    if (!std::isfinite(d) || d < lo || d > hi)
        refuse(where, fmt::format("expected a number in [{}, {}], got {}", lo, hi, describeValue(v)));
    return d;
}

int integer(const json& message, const char* key, int lo, int hi) {
    const std::string where = fmt::format("{}.{}", message.value("type", std::string()), key);
    if (!message.contains(key)) refuse(where, "missing");
    const json& v = message.at(key);
    if (!v.is_number_integer()) refuse(where, "expected an integer, got " + describeValue(v));
    const int64_t i =
        v.is_number_unsigned()
            ? static_cast<int64_t>(std::min<uint64_t>(v.get<uint64_t>(), std::numeric_limits<int64_t>::max()))
            : v.get<int64_t>();
    if (i < lo || i > hi) refuse(where, fmt::format("expected an integer in [{}, {}], got {}", lo, hi, i));
    return static_cast<int>(i);
}

glm::vec3 vec3(const json& message, const char* key, float bound) {
    const std::string where = fmt::format("{}.{}", message.value("type", std::string()), key);
    const json& v = message.at(key);
    if (!v.is_array() || v.size() != 3 ||
        !std::all_of(v.begin(), v.end(), [](const json& c) { return c.is_number(); }))
        refuse(where, "expected [x, y, z], got " + describeValue(v));
    glm::vec3 out;
    for (int i = 0; i < 3; ++i) {
        const double d = v[i].get<double>();
        if (!std::isfinite(d) || std::abs(d) > bound)
            refuse(where,
                   fmt::format("expected finite numbers within +-{}, got {}", bound, describeValue(v)));
        out[i] = static_cast<float>(d);
    }
    return out;
}

// Floats written as the doubles they are, which the scene reader reads back as the same floats.
json toJson(glm::vec3 v) {
    return json::array({static_cast<double>(v.x), static_cast<double>(v.y), static_cast<double>(v.z)});
}
json matrixJson(const glm::mat4& m) {  // 4 rows, row-major, as the scene format writes a matrix
    json rows = json::array();
    for (int row = 0; row < 4; ++row) {
        json r = json::array();
        for (int col = 0; col < 4; ++col) r.push_back(static_cast<double>(m[col][row]));
        rows.push_back(r);
    }
    return rows;
}

// A relative file name of the document, made absolute against the scene file's folder.
void makeAbsolute(json& value, const fs::path& folder) {
    if (!value.is_string()) return;
    fs::path path = value.get<std::string>();
    if (path.empty() || path.is_absolute()) return;
    value = fs::absolute(folder / path).lexically_normal().string();
}

// The options' value at a dotted path, as the page shows it.
json optionValue(const json& options, std::string_view path) {
    const json* node = &options;
    size_t start = 0;
    while (start <= path.size()) {
        const size_t dot = std::min(path.find('.', start), path.size());
        const std::string key(path.substr(start, dot - start));
        if (!node->is_object() || !node->contains(key)) return nullptr;
        node = &node->at(key);
        start = dot + 1;
    }
    return *node;
}

}  // namespace

std::optional<View> parseView(std::string_view name) {
    for (const auto& [view, n] : kViews)
        if (n == name) return view;
    return std::nullopt;
}

std::string_view viewName(View view) {
    for (const auto& [v, n] : kViews)
        if (v == view) return n;
    return "composite";
}

bool viewNeedsLayers(View view) {
    return view == View::Object || view == View::Shadow || view == View::Indirect || view == View::Depth;
}

Session::Session(const fs::path& file, const std::vector<std::string>& overrides) : file_(file) {
    std::ifstream in(file, std::ios::binary);
    if (!fs::is_regular_file(file) || !in) throw InputError(file.string(), "cannot open scene file");
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    document_ = parseJson(text, file.string());
    for (const std::string& override : overrides) applyOverride(document_, override);
    scene_ = std::make_unique<Scene>(loadScene(document_, file));
    if (!scene_->sequence.empty())
        throw InputError(
            file.string() + ": sequence",
            "a live session shows one camera; give a scene with a \"camera\" (and \"background\")");
    picking_ = std::make_unique<RayScene>(*scene_, SceneContent::RealOnly);
    const size_t entries = document_.contains("virtual") ? document_["virtual"].size() : 0;
    meshes_.resize(entries);
    for (size_t m = 0; m < scene_->virtuals.size(); ++m)
        meshes_.at(scene_->virtualEntries.at(m)).push_back(int(m));
    for (size_t k = 0; k < entries; ++k) {
        const json& entry = document_["virtual"][k];
        names_.push_back(entry.contains("name") && entry["name"].is_string()
                             ? entry["name"].get<std::string>()
                             : fmt::format("object {}", k));
        const Bounds3f b = meshBounds(int(k));
        transforms_.push_back(meshes_[k].empty() ? glm::mat4(1.0f)
                                                 : scene_->virtuals[meshes_[k][0]].worldFromObject);
        bounds_.push_back(b);
        unplaced_.push_back(false);
        contact_.push_back(b.empty() ? glm::vec3(0.0f) : glm::vec3(b.center().x, b.min.y, b.center().z));
        contactNormal_.push_back({0.0f, 1.0f, 0.0f});
    }
    fileLights_ = document_.contains("lights") ? document_["lights"].size() : 0;
    for (const TriangleMesh& m : scene_->real) realBounds_.extend(m.bounds());
}

Session::~Session() = default;

Bounds3f Session::meshBounds(int object) const {
    Bounds3f b;
    for (int m : meshes_[object]) b.extend(scene_->virtuals[m].bounds());
    return b;
}

MessageResult Session::handle(std::string_view message, int client) {
    MessageResult result;
    try {
        if (message.size() > kMaxMessageBytes)
            refuse("message", fmt::format("{} bytes, more than {}", message.size(), kMaxMessageBytes));
        const json parsed = parseJson(std::string(message), "message");
        result = dispatch(parsed);
        if (result.changed) {
            ++version_;
            lastClient_ = client;
            lastSeq_ = parsed.contains("seq") && parsed["seq"].is_number_integer()
                           ? parsed["seq"].get<int64_t>()
                           : 0;
        }
    } catch (const std::exception& e) {  // InputError, and a failure to allocate what a message asked for
        result.reply = {{"type", "error"}, {"message", e.what()}};
        result.changed = false;
    }
    return result;
}

MessageResult Session::dispatch(const json& message) {
    if (!message.is_object()) refuse("message", "expected a JSON object, got " + describeValue(message));
    if (!message.contains("type") || !message["type"].is_string())
        refuse("message", "expected a \"type\" string");
    if (message.contains("seq") && (!message["seq"].is_number_integer() || message["seq"].get<int64_t>() < 0))
        refuse("message.seq", "expected an integer >= 0");
    const std::string type = message["type"].get<std::string>();
    MessageResult result;
    result.changed = true;
    if (type == "ping") {
        allowKeys(message, {});
        result.changed = false;
        result.reply = {{"type", "pong"}};
    } else if (type == "select") {
        allowKeys(message, {"object"});
        selected_ = objectIndex(message);
    } else if (type == "drag") {
        drag(message);
    } else if (type == "rotate") {
        rotate(message);
    } else if (type == "light") {
        light(message);
    } else if (type == "options") {
        options(message);
    } else if (type == "view") {
        allowKeys(message, {"view"});
        if (!message.contains("view") || !message["view"].is_string())
            refuse("view.view", "expected a string");
        const auto view = parseView(message["view"].get<std::string>());
        if (!view)
            refuse("view.view",
                   "expected composite, background, delta, mask, object, shadow, indirect or depth, got " +
                       describeValue(message["view"]));
        if (*view == view_) {  // nothing to render again
            result.changed = false;
            result.reply = {{"type", "ok"}};
        }
        if (viewNeedsLayers(*view) != viewNeedsLayers(view_)) ++structureVersion_;
        view_ = *view;
    } else {
        refuse("message.type", "expected ping, select, drag, rotate, light, options or view, got " +
                                   describeValue(message["type"]));
    }
    return result;
}

int Session::objectIndex(const json& message) const {
    if (meshes_.empty()) refuse(message["type"].get<std::string>(), "the scene has no virtual objects");
    const int object = integer(message, "object", 0, static_cast<int>(meshes_.size()) - 1);
    if (meshes_[object].empty()) refuse(message["type"].get<std::string>(), "the object has no meshes");
    return object;
}

// Records the object's new transform in the document; its meshes follow in applyPlacements().
void Session::placeObject(int object, const glm::mat4& worldFromObject) {
    checkTransform(worldFromObject);
    transforms_[object] = worldFromObject;
    unplaced_[object] = true;
    document_["virtual"][object]["transform"] = matrixJson(worldFromObject);
}

void Session::applyPlacements() {
    for (size_t k = 0; k < meshes_.size(); ++k) {
        if (!unplaced_[k]) continue;
        unplaced_[k] = false;
        std::vector<TriangleMesh> placed;
        try {
            for (int m : meshes_[k]) placed.push_back(placedMesh(scene_->virtuals[m], transforms_[k]));
        } catch (const std::exception&) {
            // Not expected (the transform was checked, the meshes are the loaded ones): the object stays
            // where its meshes are, and the document says so.
            transforms_[k] = scene_->virtuals[meshes_[k][0]].worldFromObject;
            document_["virtual"][k]["transform"] = matrixJson(transforms_[k]);
            bounds_[k] = meshBounds(static_cast<int>(k));
            continue;
        }
        for (size_t i = 0; i < placed.size(); ++i) scene_->virtuals[meshes_[k][i]] = std::move(placed[i]);
    }
}

const Scene& Session::scene() {
    applyPlacements();
    return *scene_;
}

void Session::drag(const json& message) {
    allowKeys(message, {"object", "x", "y"});
    const int object = objectIndex(message);
    const Camera& camera = scene_->camera;
    const float x = static_cast<float>(number(message, "x", 0.0, camera.width));
    const float y = static_cast<float>(number(message, "y", 0.0, camera.height));
    const glm::vec3 direction = glm::normalize(camera.rayDirection(x, y));
    const RayHit hit = picking_->intersect(camera.position(), direction);
    if (!hit.hit()) refuse("drag", fmt::format("no real surface under pixel ({:.1f}, {:.1f})", x, y));
    // Rest the object on the surface: its box's centre along the normal, by the box's half-extent that way.
    const glm::vec3 normal = hit.geometricNormal;
    const Bounds3f bounds = bounds_[object];
    const glm::vec3 half = 0.5f * (bounds.max - bounds.min);
    const float support = glm::dot(glm::abs(normal), half);
    const glm::vec3 target = hit.position + normal * support;
    const glm::vec3 move = target - bounds.center();
    if (!(glm::length(move) < kMaxCoordinate)) refuse("drag", "the object cannot be placed there");
    placeObject(object, glm::translate(glm::mat4(1.0f), move) * transforms_[object]);
    bounds_[object] = {bounds.min + move, bounds.max + move};
    contact_[object] = hit.position;
    contactNormal_[object] = normal;
}

void Session::rotate(const json& message) {
    allowKeys(message, {"object", "degrees"});
    const int object = objectIndex(message);
    const float degrees = static_cast<float>(number(message, "degrees", -kMaxRotationDeg, kMaxRotationDeg));
    // About the normal of the surface it rests on, through its contact point: it stays where it rests.
    const glm::vec3 p = contact_[object];
    const glm::mat4 turn = glm::translate(glm::mat4(1.0f), p) *
                           glm::rotate(glm::mat4(1.0f), glm::radians(degrees), contactNormal_[object]) *
                           glm::translate(glm::mat4(1.0f), -p);
    glm::mat4 m = turn * transforms_[object];
    for (int c = 0; c < 4; ++c) m[c][3] = c == 3 ? 1.0f : 0.0f;  // affine, exactly
    placeObject(object, m);
    applyPlacements();  // its new bounds
    bounds_[object] = meshBounds(object);
}

void Session::light(const json& message) {
    allowKeys(message, {"light", "position", "intensity"});
    if (fileLights_ == 0) refuse("light", "the scene file has no lights");
    const int index = integer(message, "light", 0, static_cast<int>(fileLights_) - 1);
    Light changed = scene_->lights[index];
    json entry = document_["lights"][index];
    if (message.contains("position")) {
        if (changed.type == Light::Type::Directional)
            refuse("light.position", "a directional light has no position");
        changed.position = vec3(message, "position", kMaxCoordinate);
        entry["position"] = toJson(changed.position);
    }
    if (message.contains("intensity")) {
        const float c = std::max({changed.color.x, changed.color.y, changed.color.z, 1e-30f});
        changed.intensity = static_cast<float>(number(message, "intensity", 0.0, 1e6 / c));
        entry["intensity"] = static_cast<double>(changed.intensity);
    }
    scene_->lights[index] = changed;
    document_["lights"][index] = std::move(entry);
    ++structureVersion_;
}

void Session::options(const json& message) {
    allowKeys(message, {"values"});
    if (!message.contains("values") || !message["values"].is_object() || message["values"].empty())
        refuse("options.values", "expected an object of option values, e.g. {\"volume.resolution\": 64}");
    json options = document_.contains("options") ? document_["options"] : json::object();
    for (const auto& [key, value] : message["values"].items()) {
        if (std::find(kLiveOptions.begin(), kLiveOptions.end(), key) == kLiveOptions.end())
            refuse("options.values", fmt::format("\"{}\" is not an option of a live session",
                                                 key.size() > 64 ? key.substr(0, 64) + "..." : key));
        if (!value.is_number_integer() && !(value.is_string() && value.get<std::string>() == "auto"))
            refuse("options." + key, "expected an integer or \"auto\", got " + describeValue(value));
        const size_t dot = key.find('.');
        json& group = options[key.substr(0, dot)];
        if (!group.is_object()) group = json::object();
        group[key.substr(dot + 1)] = value;
    }
    // Checked as the scene reader checks them, then against what a live session renders in time.
    const Options parsed = readOptions(JsonNode(options, "message", "options"));
    if (parsed.volume.resolution > kMaxLiveVolumeResolution)
        refuse("options.volume.resolution", fmt::format("at most {} in a live session, got {}",
                                                        kMaxLiveVolumeResolution, parsed.volume.resolution));
    // Two renderers (the interactive frames and the idle one) keep their volumes.
    checkRenderMemory(parsed, scene_->camera, scene_->lights.size(), physicalMemoryBytes() / 2, "message");
    document_["options"] = std::move(options);
    scene_->options = parsed;
    ++structureVersion_;
}

void Session::setCameraPose(const glm::mat4& worldFromCamera) {
    scene_->camera.worldFromCamera = worldFromCamera;
}

json Session::state() const {
    const Camera& camera = scene_->camera;
    const glm::mat4 cameraFromWorld = glm::inverse(camera.worldFromCamera);
    json objects = json::array();
    for (size_t k = 0; k < meshes_.size(); ++k) {
        const glm::vec3 c = glm::vec3(cameraFromWorld * glm::vec4(contact_[k], 1.0f));
        json anchor = nullptr;
        if (c.z < 0.0f) {
            const glm::vec2 pixel = camera.imagePoint(c);
            anchor = {pixel.x, pixel.y};
        }
        objects.push_back({{"name", names_[k]}, {"anchor", anchor}, {"contact", toJson(contact_[k])}});
    }
    json lights = json::array();
    for (size_t i = 0; i < fileLights_; ++i) {
        const Light& l = scene_->lights[i];
        const json& entry = document_["lights"][i];
        lights.push_back(
            {{"name", entry.contains("name") && entry["name"].is_string() ? entry["name"].get<std::string>()
                                                                          : fmt::format("light {}", i)},
             {"type", l.type == Light::Type::Point  ? "point"
                      : l.type == Light::Type::Spot ? "spot"
                                                    : "directional"},
             {"position", toJson(l.position)},
             {"intensity", l.intensity}});
    }
    Bounds3f real = realBounds_;
    for (const Bounds3f& b : bounds_) real.extend(b);
    const json effective = optionsToJson(scene_->options);
    json options = json::object();
    for (std::string_view key : kLiveOptions) options[std::string(key)] = optionValue(effective, key);
    return {
        {"type", "state"},       {"version", version_},     {"scene", file_.filename().string()},
        {"width", camera.width}, {"height", camera.height}, {"objects", objects},
        {"selected", selected_}, {"lights", lights},        {"bounds", {toJson(real.min), toJson(real.max)}},
        {"options", options},    {"view", viewName(view_)}};
}

json Session::document() const {
    json out = document_;
    const fs::path folder = file_.parent_path();
    if (out.contains("background")) makeAbsolute(out["background"], folder);
    if (out.contains("environment") && out["environment"].is_object() && out["environment"].contains("file"))
        makeAbsolute(out["environment"]["file"], folder);
    for (const char* list : {"scene", "virtual"})
        if (out.contains(list) && out[list].is_array())
            for (json& entry : out[list])
                if (entry.is_object() && entry.contains("file")) makeAbsolute(entry["file"], folder);
    return out;
}

Options interactiveOptions(const Options& full, int width, int height, size_t lightCount, int scale) {
    Options o = full;
    o.render.samplesPerPixel = 1;
    auto sparser = [&](int& option, int autoStride) {
        option = std::max(std::min(2 * pixelStrideFor(option, autoStride, width, height), 32) / scale, 1);
    };
    sparser(o.diffuse.pixelStride, kAutoDiffuseStride);
    sparser(o.diffuse.relightPixelStride, kAutoRelightDiffuseStride);
    sparser(o.specular.relightPixelStride, kAutoRelightSpecularStride);
    sparser(o.diffuse.objectRayPixelStride, kAutoObjectRayStride);
    sparser(o.shadow.pixelStride, kAutoShadowStride);
    // Half the reflective shadow maps' side: a quarter of the texels to trace again and inject. "auto" gives
    // each of several lights its own share, which one number cannot; it is halved for a single light only.
    if (o.rsm.resolution > 0)
        o.rsm.resolution = std::max(kAutoRsmMinResolution, o.rsm.resolution / 2);
    else if (lightCount == 1)
        o.rsm.resolution =
            std::max(kAutoRsmMinResolution, rsmResolutionCeiling(0, o.volume.resolution, false) / 2);
    o.diffuse.objectRays = std::min(o.diffuse.objectRays, 4);
    sparser(o.shadow.relightPixelStride, kAutoRelightShadowStride);
    return o;
}

bool canReduceResolution(int width, int height, int scale) {
    return scale > 1 && width % scale == 0 && height % scale == 0 && width / scale >= 64 &&
           height / scale >= 48;
}

int interactiveScene(const Scene& scene, const Options& options, int scale, Scene& out) {
    out = scene;
    out.options = options;
    if (!canReduceResolution(scene.camera.width, scene.camera.height, scale)) return 1;
    Camera& c = out.camera;
    const float inverse = 1.0f / static_cast<float>(scale);
    c.width /= scale;
    c.height /= scale;
    c.fx *= inverse;
    c.fy *= inverse;
    c.cx *= inverse;  // continuous image coordinates: the image's corners stay its corners
    c.cy *= inverse;
    if (scene.background) out.background = reducedImage(*scene.background, scale);
    return scale;
}

Image reducedImage(const Image& image, int scale) {
    if (scale <= 1) return image;
    const int width = image.width() / scale, height = image.height() / scale, channels = image.channels();
    Image small(width, height, channels, 0.0f);
    const float weight = 1.0f / static_cast<float>(scale * scale);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int ch = 0; ch < channels; ++ch) {
                float sum = 0.0f;
                for (int dy = 0; dy < scale; ++dy)
                    for (int dx = 0; dx < scale; ++dx) sum += image.at(x * scale + dx, y * scale + dy, ch);
                small.at(x, y, ch) = sum * weight;
            }
    return small;
}

namespace {

uint8_t linear8(float v) {
    if (!(v > 0.0f)) return 0;
    if (v >= 1.0f) return 255;
    return static_cast<uint8_t>(v * 255.0f + 0.5f);
}

}  // namespace

std::vector<uint8_t> viewPixels(const RenderOutput& output, View view) {
    const Image& reference = output.composite;
    const int width = reference.width(), height = reference.height();
    std::vector<uint8_t> rgb(static_cast<size_t>(width) * height * 3, 0);
    auto each = [&](const Image& image, auto&& pixel) {
        if (image.width() != width || image.height() != height) return;
        const int channels = image.channels();
        const std::span<const float> data = image.data();
        for (size_t i = 0; i < static_cast<size_t>(width) * height; ++i) pixel(i, &data[i * channels]);
    };
    auto colour = [&](const Image& image) {
        each(image, [&](size_t i, const float* p) {
            for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = linearToSrgb8(p[image.channels() >= 3 ? c : 0]);
        });
    };
    auto change = [&](const Image& image) {  // grey 0.5 + 4 x the change, as the README's delta pictures
        each(image, [&](size_t i, const float* p) {
            for (int c = 0; c < 3; ++c)
                rgb[i * 3 + c] = linear8(0.5f + 4.0f * (std::isfinite(p[c]) ? p[c] : 0.0f));
        });
    };
    switch (view) {
        case View::Composite:
            colour(output.composite);
            break;
        case View::Background:
            colour(output.background);
            break;
        case View::Delta:
            change(output.delta);
            break;
        case View::Mask:
            each(output.objectMask, [&](size_t i, const float* p) {
                rgb[i * 3] = rgb[i * 3 + 1] = rgb[i * 3 + 2] = linear8(p[0]);
            });
            break;
        case View::Object:
            colour(output.object);
            break;
        case View::Shadow:
            change(output.shadow);
            break;
        case View::Indirect:
            change(output.indirect);
            break;
        case View::Depth: {
            float lo = std::numeric_limits<float>::infinity(), hi = 0.0f;
            for (float d : output.depth.data())
                if (std::isfinite(d)) lo = std::min(lo, d), hi = std::max(hi, d);
            const float range = hi > lo ? hi - lo : 1.0f;
            each(output.depth, [&](size_t i, const float* p) {  // near white, far dark, none black
                const uint8_t v = std::isfinite(p[0]) ? linear8(1.0f - 0.8f * (p[0] - lo) / range) : 0;
                rgb[i * 3] = rgb[i * 3 + 1] = rgb[i * 3 + 2] = v;
            });
            break;
        }
    }
    return rgb;
}

std::string encodeJpeg(const std::vector<uint8_t>& rgb, int width, int height, int quality) {
    if (width <= 0 || height <= 0 || rgb.size() != static_cast<size_t>(width) * height * 3)
        throw InputError("live session", "bad frame size");
    try {
        return encodeJpeg8(rgb, width, height, quality);
    } catch (const ImageCodecError& e) {
        throw InputError("live session", e.what());
    }
}

Image decodeCameraFrame(std::string_view jpeg, int width, int height) {
    const std::string where = "camera frame";
    if (jpeg.size() < 3 || static_cast<unsigned char>(jpeg[0]) != 0xFF ||
        static_cast<unsigned char>(jpeg[1]) != 0xD8 || static_cast<unsigned char>(jpeg[2]) != 0xFF)
        throw InputError(where, fmt::format("{} bytes that are not a JPEG image", jpeg.size()));
    std::unique_ptr<ImageDecoder> input;
    try {
        input = openImageBytes(std::as_bytes(std::span(jpeg.data(), jpeg.size())), ImageFormat::Jpeg);
    } catch (const ImageCodecError& e) {
        throw InputError(where, fmt::format("cannot decode the JPEG image: {}", e.what()));
    }
    const ImageHeader& spec = input->header();
    // The header's size is checked before any pixel is decoded.
    if (spec.width != width || spec.height != height)
        throw InputError(where, fmt::format("{}x{}, the scene camera is {}x{}: send frames of its size",
                                            spec.width, spec.height, width, height));
    if (spec.channels != 1 && spec.channels != 3)
        throw InputError(where, fmt::format("{} channels: expected RGB or grey", spec.channels));
    std::vector<uint8_t> pixels(static_cast<size_t>(width) * height * spec.channels);
    try {
        input->readUInt8(pixels);
    } catch (const ImageCodecError& e) {
        throw InputError(where, fmt::format("cannot decode the JPEG image: {}", e.what()));
    }
    const std::array<float, 256>& linear = srgb8ToLinearValues();
    Image image(width, height, 3);
    std::span<float> out = image.data();
    const size_t count = static_cast<size_t>(width) * height;
    for (size_t i = 0; i < count; ++i)
        for (int c = 0; c < 3; ++c)
            out[i * 3 + c] = linear[pixels[i * spec.channels + (spec.channels == 3 ? c : 0)]];
    return image;
}

std::string encodePng(const Image& image) {
    return encodePngBytes(image, "live session");
}

std::string jsonText(const json& value, int indent) {
    return value.dump(indent, ' ', false, json::error_handler_t::replace);
}

json timingsJson(const RenderOutput& output) {
    json stages = json::array();
    for (const StageTiming& t : output.timings) stages.push_back({t.name, std::round(t.ms * 100.0) / 100.0});
    return {{"stages", stages}, {"total_ms", std::round(output.totalMs * 100.0) / 100.0}};
}

}  // namespace deltagi::live
