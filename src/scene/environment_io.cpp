#include "scene/environment_io.h"

#include <algorithm>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "core/environment.h"
#include "deltagi/error.h"

namespace deltagi {

namespace fs = std::filesystem;

namespace {

// [x, y] in pixels.
glm::vec2 readPixel(const JsonNode& node) {
    if (!node.value().is_array() || node.size() != 2)
        node.fail("expected [x, y] (2 numbers, pixels), got " + describeValue(node.value()));
    return {node.element(0).floatNumber(), node.element(1).floatNumber()};
}

// The circle's centre and radius default to the image's centre and the largest circle inside the image.
void readCircle(const std::optional<JsonNode>& node, const Image& image, glm::vec2& center, float& radius) {
    center = 0.5f * glm::vec2(image.width(), image.height());
    radius = 0.5f * static_cast<float>(std::min(image.width(), image.height()));
    if (!node) return;
    if (auto n = node->find("center")) center = readPixel(*n);
    if (auto n = node->find("radius")) radius = n->floatNumber(kPositive);
}

FisheyeProjection readFisheye(const std::optional<JsonNode>& node, const Image& image) {
    FisheyeProjection p;
    if (node) node->allowKeys({"model", "center", "radius", "fov_deg"});
    readCircle(node, image, p.center, p.radius);
    if (!node) return p;
    if (auto n = node->find("model")) {
        const std::string model = n->string();
        if (model == "equidistant")
            p.model = FisheyeProjection::Model::Equidistant;
        else if (model == "equisolid")
            p.model = FisheyeProjection::Model::Equisolid;
        else
            n->fail("expected \"equidistant\" or \"equisolid\", got \"" + model + "\"");
    }
    if (auto n = node->find("fov_deg")) p.fovDeg = n->floatNumber({0.0, 360.0, true, false});
    return p;
}

MirrorBallProjection readMirrorBall(const std::optional<JsonNode>& node, const Image& image) {
    MirrorBallProjection p;
    if (node) node->allowKeys({"center", "radius"});
    readCircle(node, image, p.center, p.radius);
    return p;
}

// Rotation in degrees about x, then y, then z (R = Rz Ry Rx), as in mesh transforms.
glm::mat3 readRotation(const JsonNode& node) {
    const glm::vec3 deg = node.vec3();
    glm::mat4 m(1.0f);
    m = glm::rotate(m, glm::radians(deg.z), glm::vec3(0, 0, 1));
    m = glm::rotate(m, glm::radians(deg.y), glm::vec3(0, 1, 0));
    m = glm::rotate(m, glm::radians(deg.x), glm::vec3(1, 0, 0));
    return glm::mat3(m);
}

}  // namespace

namespace {

// The rotation and the keys allowed, shared by the file and the light camera.
void checkEnvironmentKeys(const JsonNode& node) {
    node.requireObject();
    node.allowKeys({"file", "projection", "fisheye", "mirror_ball", "rotate_deg", "intensity"});
}

}  // namespace

Environment environmentFromImage(const JsonNode& node, Image image, const std::string& imageName,
                                 std::optional<EquirectConversion>* conversion) {
    checkEnvironmentKeys(node);
    Environment environment;
    std::string projection = "equirectangular";
    if (auto n = node.find("projection")) {
        projection = n->string();
        if (projection != "equirectangular" && projection != "fisheye" && projection != "mirror_ball")
            n->fail("expected \"equirectangular\", \"fisheye\" or \"mirror_ball\", got \"" + projection +
                    "\"");
    }
    for (const char* key : {"fisheye", "mirror_ball"})
        if (node.has(key) && projection != key)
            node.child(key).fail(
                fmt::format("only allowed with \"projection\": \"{}\" (it is \"{}\")", key, projection));
    float intensity = 1.0f;
    if (auto n = node.find("intensity")) intensity = n->floatNumber(kNonNegative);
    if (auto n = node.find("rotate_deg")) environment.worldFromEnvironment = readRotation(*n);
    if (projection == "equirectangular") {
        if (image.width() != 2 * image.height())
            throw InputError(imageName,
                             fmt::format("expected an equirectangular image twice as wide as high, "
                                         "got {}x{}",
                                         image.width(), image.height()));
        environment.radiance = std::move(image);
    } else {
        // The projection's parameters are read (and checked) for every image; its conversion is made again
        // only for an image of another size.
        const bool fisheye = projection == "fisheye";
        const FisheyeProjection f = fisheye ? readFisheye(node.find("fisheye"), image) : FisheyeProjection{};
        const MirrorBallProjection b =
            fisheye ? MirrorBallProjection{} : readMirrorBall(node.find("mirror_ball"), image);
        std::optional<EquirectConversion> local;
        std::optional<EquirectConversion>& kept = conversion ? *conversion : local;
        if (!kept || kept->sourceWidth() != image.width() || kept->sourceHeight() != image.height())
            kept = fisheye ? EquirectConversion::fromFisheye(image.width(), image.height(), f)
                           : EquirectConversion::fromMirrorBall(image.width(), image.height(), b);
        environment.radiance = kept->apply(image);
    }
    float brightest = 0.0f;
    for (float& v : environment.radiance.data()) brightest = std::max(brightest, v *= intensity);
    if (!(brightest <= static_cast<float>(kMaxRadiance)))
        throw InputError(
            node.childWhere("intensity"),
            fmt::format("the brightest pixel of '{}' times intensity is {:.3g}, more than {:.0e}, "
                        "beyond which the render's 32-bit floats overflow",
                        imageName, brightest, kMaxRadiance));
    return environment;
}

void readEnvironment(const JsonNode& node, const fs::path& sceneFolder, Scene& scene) {
    checkEnvironmentKeys(node);
    const JsonNode fileNode = node.child("file");
    const fs::path file = inputFile(fileNode, sceneFolder);
    const std::string fileName = file.string();
    ImageFile read;
    try {
        read = readImageFile(file);
    } catch (const InputError& e) {
        fileNode.fail(e.what());
    }
    Image& image = read.image;
    if (!read.floatPixels)
        scene.warnings.push_back(
            fmt::format("{}: '{}' is a low-dynamic-range image: decoded from sRGB, but its brightest parts "
                        "(the sun, lamps) "
                        "are clipped, so it lights the scene too weakly; use an .hdr or .exr light probe",
                        fileNode.where(), fileName));
    if (const size_t bad = sanitizeRadiance(image); bad > 0)
        scene.warnings.push_back(
            fmt::format("{}: {} of {} pixels of '{}' are NaN, infinite or negative: set to 0",
                        fileNode.where(), bad, image.pixelCount(), fileName));
    Environment environment;
    try {
        environment = environmentFromImage(node, std::move(image), fileName);
    } catch (const InputError& e) {
        if (e.where() == fileName) fileNode.fail(e.message() + fmt::format(" ('{}')", fileName));
        throw;
    }
    environment.file = file;
    setEnvironment(scene, std::move(environment));
}

}  // namespace deltagi
