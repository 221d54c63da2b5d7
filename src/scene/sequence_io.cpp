#include "deltagi/scene_io.h"

#include <algorithm>
#include <fstream>
#include <iterator>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/keyframes.h"
#include "deltagi/transforms.h"
#include "scene/json_reader.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace deltagi {

namespace {

constexpr int kMaxImageSide = 16384;

// A per-frame key, else the file's global one, else nothing.
std::optional<JsonNode> intrinsic(const JsonNode& frame, const JsonNode& root, std::string_view key) {
    if (auto n = frame.find(key)) return n;
    return root.find(key);
}

Camera readFrameCamera(const JsonNode& frame, const JsonNode& root) {
    auto need = [&](std::string_view key) {
        if (auto n = intrinsic(frame, root, key)) return *n;
        frame.fail(fmt::format("missing \"{}\" (neither in the frame nor at the top of the file)", key));
    };
    Camera camera;
    camera.width = need("w").integer(1, kMaxImageSide);
    camera.height = need("h").integer(1, kMaxImageSide);
    if (auto fx = intrinsic(frame, root, "fl_x")) {
        camera.fx = fx->floatNumber({0.0, 1e9, true, false});
        auto fy = intrinsic(frame, root, "fl_y");
        camera.fy = fy ? fy->floatNumber({0.0, 1e9, true, false}) : camera.fx;
    } else if (auto angle = intrinsic(frame, root, "camera_angle_x")) {
        const double radians = angle->number({0.0, 3.14159, true, true});
        camera.fx = camera.fy = static_cast<float>(0.5 * camera.width / std::tan(0.5 * radians));
    } else {
        frame.fail("missing focal length: give \"fl_x\" (and \"fl_y\") or \"camera_angle_x\"");
    }
    auto cx = intrinsic(frame, root, "cx"), cy = intrinsic(frame, root, "cy");
    camera.cx = cx ? cx->floatNumber() : 0.5f * static_cast<float>(camera.width);
    camera.cy = cy ? cy->floatNumber() : 0.5f * static_cast<float>(camera.height);

    auto coefficient = [&](std::string_view key) {
        auto n = intrinsic(frame, root, key);
        return n ? n->floatNumber({-1e3, 1e3, false, false}) : 0.0f;
    };
    auto modelNode = intrinsic(frame, root, "camera_model");
    const std::string model = modelNode ? modelNode->string() : "";
    if (model == "OPENCV" ||
        (model.empty() && (intrinsic(frame, root, "k1") || intrinsic(frame, root, "p1"))))
        camera.distortion = lensDistortion(LensDistortion::Model::OpenCV, coefficient);
    else if (model == "OPENCV_FISHEYE")
        camera.distortion = lensDistortion(LensDistortion::Model::Fisheye, coefficient);
    else if (!model.empty() && model != "PINHOLE" && model != "SIMPLE_PINHOLE")
        modelNode->fail("unknown camera model \"" + model + "\": expected PINHOLE, OPENCV or OPENCV_FISHEYE");
    const LensDistortion& d = camera.distortion;
    if (d.model == LensDistortion::Model::OpenCV && d.k1 == 0 && d.k2 == 0 && d.k3 == 0 && d.p1 == 0 &&
        d.p2 == 0)
        camera.distortion.model = LensDistortion::Model::None;

    const JsonNode matrix = frame.child("transform_matrix");
    camera.worldFromCamera = matrix.matrix4();
    const float det = glm::determinant(glm::mat3(camera.worldFromCamera));
    if (!(std::abs(det) > 1e-6f))
        matrix.fail(fmt::format("the camera's rotation is singular (determinant {:.3g})", det));
    const glm::mat4& m = camera.worldFromCamera;  // column-major: m[column][row]
    if (m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f)
        matrix.fail("expected the last row [0, 0, 0, 1]");
    // A scaled, sheared or mirrored pose would fail only when the frame is rendered, without the file's name.
    try {
        checkCameraPose(camera.worldFromCamera);
    } catch (const InputError& e) {
        matrix.fail(e.message());
    }
    return camera;
}

// The frame's photo: file_path relative to the transforms file; without an extension, .png or .jpg. Empty
// for a frame without file_path: a camera path over the real scene rendered as it is.
fs::path framePhoto(const JsonNode& frame, const fs::path& folder) {
    const auto found = frame.find("file_path");
    if (!found) return {};
    const JsonNode& pathNode = *found;
    const fs::path given = folder / pathNode.string();
    if (fs::is_regular_file(given)) return given;
    if (!given.has_extension())
        for (const char* ext : {".png", ".jpg", ".jpeg", ".exr"}) {
            fs::path withExt = given;
            withExt += ext;
            if (fs::is_regular_file(withExt)) return withExt;
        }
    pathNode.fail(fmt::format("photo not found: '{}'", given.string()));
}

}  // namespace

FrameRange parseFrameRange(const std::string& text, const std::string& where) {
    const size_t colon = text.find(':');
    auto number = [&](const std::string& part, int fallback) {
        if (part.empty()) return fallback;
        if (part.size() > 9 || part.find_first_not_of("0123456789") != std::string::npos)
            throw InputError(where,
                             fmt::format("expected a frame range A:B (A included, B not), got '{}'", text));
        return std::stoi(part);
    };
    if (colon == std::string::npos)
        throw InputError(where,
                         fmt::format("expected a frame range A:B (A included, B not), got '{}'", text));
    FrameRange range{number(text.substr(0, colon), 0), number(text.substr(colon + 1), -1)};
    if (range.last >= 0 && range.last <= range.first)
        throw InputError(where, fmt::format("the frame range '{}' is empty", text));
    return range;
}

namespace {

json readTransformsDocument(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!fs::is_regular_file(file) || !in) throw InputError(file.string(), "cannot open the transforms file");
    const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    return parseJson(text, file.string());
}

// The document's "frames", checked to be a non-empty array.
JsonNode framesOf(const JsonNode& root) {
    root.requireObject();
    JsonNode frames = root.child("frames");
    frames.requireArray();
    if (frames.size() == 0) frames.fail("no frames");
    return frames;
}

}  // namespace

std::vector<SequenceFrame> readTransforms(const fs::path& file, FrameRange range) {
    const json document = readTransformsDocument(file);
    const JsonNode root(document, file.string());
    const JsonNode frames = framesOf(root);
    const int count = static_cast<int>(frames.size());
    const int last = range.last < 0 ? count : range.last;
    if (range.first >= count || last > count)
        frames.fail(fmt::format("the frame range {}:{} is outside the file's {} frames (0:{})", range.first,
                                range.last < 0 ? std::string() : std::to_string(range.last), count, count));
    // Photos for every frame, or for none (a camera path over the rendered real scene): a frame without one
    // among frames with one is a mistake, not a frame to render differently.
    size_t withPhoto = 0, firstWithout = frames.size();
    for (size_t i = 0; i < frames.size(); ++i) {
        const nlohmann::json& frame = frames.element(i).value();
        if (frame.is_object() && frame.contains("file_path"))
            ++withPhoto;
        else if (firstWithout == frames.size())
            firstWithout = i;
    }
    if (withPhoto > 0 && firstWithout < frames.size())
        frames.element(firstWithout)
            .fail(
                fmt::format("no \"file_path\", while {} of the {} frames have a photo: give every frame its "
                            "photo, or none (a camera path over the rendered real scene)",
                            withPhoto, frames.size()));
    std::vector<SequenceFrame> out;
    for (int i = range.first; i < last; ++i) {
        const JsonNode frame = frames.element(static_cast<size_t>(i));
        frame.requireObject();
        out.push_back({i, readFrameCamera(frame, root), framePhoto(frame, file.parent_path())});
        // A photo of the wrong size fails now, from its header, not after the frames before it are rendered.
        const Camera& camera = out.back().camera;
        if (const auto size = out.back().photo.empty() ? std::nullopt : imageFileSize(out.back().photo);
            size && (size->first != camera.width || size->second != camera.height))
            frame.child("file_path")
                .fail(fmt::format("expected a photo of the camera's size {}x{}, got {}x{} ('{}')",
                                  camera.width, camera.height, size->first, size->second,
                                  out.back().photo.string()));
    }
    return out;
}

glm::vec3 sequenceViewpoint(const fs::path& file) {
    const json document = readTransformsDocument(file);
    const JsonNode root(document, file.string());
    const JsonNode first = framesOf(root).element(0);
    first.requireObject();
    return readFrameCamera(first, root).position();
}

std::optional<double> transformsFrameRate(const fs::path& file) {
    const json document = readTransformsDocument(file);
    const JsonNode root(document, file.string());
    root.requireObject();
    if (auto n = root.find("fps")) return n->number({0.0, kMaxFrameRate, true, false});
    return std::nullopt;
}

Image readFramePhoto(const SequenceFrame& frame, const fs::path& transformsFile) {
    const std::string where = fmt::format("{}: frames[{}].file_path", transformsFile.string(), frame.index);
    Image photo;
    try {
        photo = readImage(frame.photo);
    } catch (const InputError& e) {
        throw InputError(where, e.what());
    }
    if (photo.width() != frame.camera.width || photo.height() != frame.camera.height)
        throw InputError(where, fmt::format("expected a photo of the camera's size {}x{}, got {}x{} ('{}')",
                                            frame.camera.width, frame.camera.height, photo.width(),
                                            photo.height(), frame.photo.string()));
    return photo;
}

void showFrame(Scene& scene, const SequenceFrame& frame) {
    scene.camera = frame.camera;
    scene.background =
        frame.photo.empty() ? std::nullopt : std::optional<Image>(readFramePhoto(frame, scene.sequenceFile));
    scene.backgroundFile = frame.photo;
    poseObjects(scene, frame.index);
}

ShownFrame shownFrame(const Scene& scene) {
    return {scene.camera, scene.background, scene.backgroundFile};
}

void restoreShownFrame(Scene& scene, const ShownFrame& shown) {
    scene.camera = shown.camera;
    scene.background = shown.background;
    scene.backgroundFile = shown.backgroundFile;
    if (!scene.sequence.empty()) poseObjects(scene, scene.sequence.front().index);
}

std::string sequenceRangeText(const Scene& scene) {
    if (scene.sequence.empty()) return {};
    return fmt::format("frames {}:{} of {}", scene.sequence.front().index, scene.sequence.back().index + 1,
                       scene.sequenceFile.string());
}

std::vector<SequenceFrame> framesBeforeSequence(const Scene& scene) {
    if (scene.sequence.empty()) return {};
    const int first = scene.sequence.front().index;
    const int before = std::min(scene.options.render.temporalFrames - 1, first);
    if (before <= 0) return {};
    return readTransforms(scene.sequenceFile, {first - before, first});
}

}  // namespace deltagi
