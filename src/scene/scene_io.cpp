// Reading scene files: JSON -> Scene. The format is documented in docs/scene-format.md; every check here
// raises InputError naming the file and the JSON path of the key ("scene.json: scene[2].material.albedo").
#include "deltagi/scene_io.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iterator>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/error.h"
#include "deltagi/keyframes.h"
#include "deltagi/renderer.h"
#include "deltagi/transforms.h"
#include "scene/environment_io.h"
#include "scene/json_reader.h"
#include "scene/keyframes_io.h"
#include "scene/material_io.h"
#include "scene/mesh_io.h"
#include "scene/option_table.h"
#include "scene/scene_info.h"
#include "scene/scene_reader.h"
#include "scene/shapes.h"

namespace deltagi {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kMaxImageSide = 16384;     // camera width and height
constexpr int kMaxShapeSegments = 4096;  // sphere and torus tessellation

}  // namespace

// ---- files ------------------------------------------------------------------------------------------------

fs::path inputFile(const JsonNode& node, const fs::path& sceneFolder) {
    fs::path path = node.string();
    if (path.empty()) node.fail("expected a file name, got an empty string");
    if (path.is_relative()) path = sceneFolder / path;
    path = path.lexically_normal();
    std::error_code error;  // a symbolic link loop, a folder that cannot be searched: said, not thrown
    const fs::file_status status = fs::status(path, error);
    if (fs::is_regular_file(status)) return path;
    if (fs::is_directory(status)) node.fail(fmt::format("'{}' is a folder, expected a file", path.string()));
    if (fs::exists(status))
        node.fail(fmt::format("'{}' is not a regular file (a device, a FIFO, a socket)", path.string()));
    if (error && error != std::errc::no_such_file_or_directory)
        node.fail(fmt::format("cannot read '{}': {}", path.string(), error.message()));
    std::string hint;
    for (const fs::path& part : path.parent_path())
        if (part == "shared")
            hint = " (this example needs ../shared/data from the project's shared data set)";
    node.fail(fmt::format("file not found: '{}'{}", path.string(), hint));
}

namespace {

std::string sizeText(int width, int height) {
    return fmt::format("{}x{}", width, height);
}

// ---- camera -----------------------------------------------------------------------------------------------

void readIntrinsics(const JsonNode& node, Camera& camera) {
    bool pinhole = node.has("fx") || node.has("fy") || node.has("cx") || node.has("cy");
    if (auto fov = node.find("fov_y_deg")) {
        if (pinhole) fov->fail("give either fov_y_deg or fx, fy (cx, cy), not both");
        camera.setFieldOfView(fov->number({0.0, 180.0, true, true}));
        return;
    }
    if (!pinhole)
        node.fail(
            "missing intrinsics: give \"fx\" and \"fy\" (and optionally \"cx\", \"cy\"), or \"fov_y_deg\"");
    camera.fx = node.child("fx").floatNumber(kPositive);
    camera.fy = node.child("fy").floatNumber(kPositive);
    camera.cx = node.has("cx") ? node.child("cx").floatNumber() : 0.5f * static_cast<float>(camera.width);
    camera.cy = node.has("cy") ? node.child("cy").floatNumber() : 0.5f * static_cast<float>(camera.height);
}

// "distortion": {"model": "opencv", "k1", "k2", "k3", "p1", "p2"} or {"model": "fisheye", "k1".."k4"}, each
// coefficient 0 unless given.
LensDistortion readDistortion(const JsonNode& node) {
    const JsonNode modelNode = node.child("model");
    const std::string model = modelNode.string();
    auto coefficient = [&](std::string_view key) {
        auto n = node.find(key);
        return n ? n->floatNumber({-1e3, 1e3, false, false}) : 0.0f;
    };
    if (model == "opencv") {
        node.allowKeys({"model", "k1", "k2", "k3", "p1", "p2"});
        return lensDistortion(LensDistortion::Model::OpenCV, coefficient);
    }
    if (model == "fisheye") {
        node.allowKeys({"model", "k1", "k2", "k3", "k4"});
        return lensDistortion(LensDistortion::Model::Fisheye, coefficient);
    }
    if (model != "none")
        modelNode.fail("expected \"opencv\", \"fisheye\" or \"none\", got \"" + model + "\"");
    return {};
}

// The camera's pose: the checks are deltagi/transforms.h's, which name the key; here under the JSON path.
glm::mat4 lookAtPose(const JsonNode& node) {
    glm::vec3 position = node.child("position").vec3();
    glm::vec3 lookAt = node.child("look_at").vec3();
    glm::vec3 up = node.has("up") ? node.child("up").vec3() : glm::vec3(0.0f, 1.0f, 0.0f);
    try {
        return deltagi::lookAtPose(position, lookAt, up);
    } catch (const InputError& e) {
        throw InputError(node.childWhere(e.where()), e.message());
    }
}

glm::mat4 matrixPose(const JsonNode& node) {
    glm::mat4 m = node.matrix4();
    try {
        checkCameraPose(m);
    } catch (const InputError& e) {
        node.fail(e.message());
    }
    return m;
}

Camera readCamera(const JsonNode& node) {
    node.allowKeys({"width", "height", "fx", "fy", "cx", "cy", "fov_y_deg", "position", "look_at", "up",
                    "world_from_camera", "distortion"});
    Camera camera;
    camera.width = node.child("width").integer(1, kMaxImageSide);
    camera.height = node.child("height").integer(1, kMaxImageSide);
    readIntrinsics(node, camera);
    if (auto n = node.find("distortion")) camera.distortion = readDistortion(*n);
    bool lookAt = node.has("position") || node.has("look_at") || node.has("up");
    if (auto matrix = node.find("world_from_camera")) {
        if (lookAt) matrix->fail("give either world_from_camera or position, look_at (up), not both");
        camera.worldFromCamera = matrixPose(*matrix);
    } else if (lookAt) {
        camera.worldFromCamera = lookAtPose(node);
    } else {
        node.fail(
            "missing pose: give \"position\" and \"look_at\" (and optionally \"up\"), or "
            "\"world_from_camera\"");
    }
    return camera;
}

// ---- lights -----------------------------------------------------------------------------------------------

glm::vec3 readDirection(const JsonNode& node) {
    glm::vec3 direction = node.vec3();
    float length = glm::length(direction);
    if (!(length > 0.0f) || !std::isfinite(length)) node.fail("expected a non-zero direction");
    return direction / length;
}

Light readLight(const JsonNode& node) {
    node.requireObject();
    JsonNode typeNode = node.child("type");
    std::string type = typeNode.string();
    Light light;
    if (type == "point") {
        light.type = Light::Type::Point;
        node.allowKeys({"type", "name", "color", "intensity", "radius", "position"});
    } else if (type == "spot") {
        light.type = Light::Type::Spot;
        node.allowKeys({"type", "name", "color", "intensity", "radius", "position", "direction",
                        "inner_angle_deg", "outer_angle_deg"});
    } else if (type == "directional") {
        light.type = Light::Type::Directional;
        node.allowKeys({"type", "name", "color", "intensity", "direction"});
    } else {
        typeNode.fail("expected \"point\", \"spot\" or \"directional\", got \"" + type + "\"");
    }
    if (auto n = node.find("name")) n->string();  // only for the reader of the file
    if (auto n = node.find("color")) light.color = n->vec3(kNonNegative);
    if (auto n = node.find("intensity")) light.intensity = n->floatNumber(kNonNegative);
    if (const double power =
            static_cast<double>(light.intensity) * std::max({light.color.x, light.color.y, light.color.z});
        power > static_cast<float>(kMaxRadiance))
        throw InputError(node.childWhere("intensity"),
                         fmt::format("intensity times color is {:.3g}, more than {:.0e}, beyond which the "
                                     "render's 32-bit floats overflow",
                                     power, kMaxRadiance));
    if (auto n = node.find("radius")) light.radius = n->floatNumber(kNonNegative);
    if (type != "directional") light.position = node.child("position").vec3();
    if (type != "point") light.direction = readDirection(node.child("direction"));
    if (type == "spot") {
        constexpr Interval kHalfAngle{0.0, 90.0};
        if (auto n = node.find("inner_angle_deg")) light.innerAngleDeg = n->floatNumber(kHalfAngle);
        if (auto n = node.find("outer_angle_deg")) light.outerAngleDeg = n->floatNumber(kHalfAngle);
        if (light.innerAngleDeg > light.outerAngleDeg)
            throw InputError(node.childWhere("inner_angle_deg"),
                             fmt::format("expected at most outer_angle_deg ({}), got {}", light.outerAngleDeg,
                                         light.innerAngleDeg));
    }
    return light;
}

// ---- mesh entries -----------------------------------------------------------------------------------------

// What reading the mesh entries shares: the scene file's folder, the mesh files read, the textures (each
// read once) and the warnings.
struct MeshInputs {
    fs::path sceneFolder;
    std::vector<fs::path>& files;
    std::vector<std::string>& warnings;
    TextureCache textures;
    // The memory guard, given the triangles read so far after each entry (`where` names the entry).
    std::function<void(uint64_t triangles, const std::string& where)> checkMemory;
    uint64_t triangles = 0;
};

glm::vec3 readScale(const JsonNode& node) {
    glm::vec3 scale = node.value().is_number() ? glm::vec3(node.floatNumber()) : node.vec3();
    if (scale.x == 0.0f || scale.y == 0.0f || scale.z == 0.0f)
        node.fail("expected non-zero scale factors (a zero scale flattens the mesh)");
    return scale;
}

// Object form: T * R * S with R = Rz * Ry * Rx (rotated about X first). Array form: 4 rows, row-major.
glm::mat4 readTransform(const JsonNode& node) {
    if (node.value().is_array()) {
        glm::mat4 m = node.matrix4();
        try {
            checkTransform(m);
        } catch (const InputError& e) {
            node.fail(e.message());
        }
        return m;
    }
    node.allowKeys({"translate", "rotate_deg", "scale"});
    glm::vec3 translate(0.0f), rotateDeg(0.0f), scale(1.0f);
    if (auto n = node.find("translate")) translate = n->vec3();
    if (auto n = node.find("rotate_deg")) rotateDeg = n->vec3();
    if (auto n = node.find("scale")) scale = readScale(*n);
    glm::mat4 m = glm::translate(glm::mat4(1.0f), translate);
    m = glm::rotate(m, glm::radians(rotateDeg.z), glm::vec3(0, 0, 1));
    m = glm::rotate(m, glm::radians(rotateDeg.y), glm::vec3(0, 1, 0));
    m = glm::rotate(m, glm::radians(rotateDeg.x), glm::vec3(1, 0, 0));
    return glm::scale(m, scale);
}

// "markers": [{"id": 0, "size": 0.12, "transform": ...}]: AprilTag tag36h11 markers lying on the real scene.
// The transform must be rigid (a printed square keeps its size): its rotation orthonormal to 1e-3.
constexpr int kTag36h11Codes = 587;
Marker readMarker(const JsonNode& node) {
    node.requireObject();
    node.allowKeys({"id", "size", "transform", "family"});
    if (auto family = node.find("family"); family && family->string() != "tag36h11")
        family->fail("expected \"tag36h11\" (AprilTag), got \"" + family->string() + "\"");
    Marker marker;
    marker.id = node.child("id").integer(0, kTag36h11Codes - 1);
    marker.size = node.child("size").floatNumber({0.0, 1e6, true, false});
    const JsonNode transform = node.child("transform");
    marker.worldFromMarker = readTransform(transform);
    const glm::mat3 r(marker.worldFromMarker);
    const glm::mat3 gram = glm::transpose(r) * r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (std::abs(gram[i][j] - (i == j ? 1.0f : 0.0f)) > 1e-3f || !std::isfinite(gram[i][j]))
                transform.fail(
                    "expected a rotation and a translation only (a marker keeps its printed size)");
    if (glm::determinant(r) < 0.0f) transform.fail("expected a rotation, got a mirroring");
    return marker;
}

// "indices": [[i, j, k], ...] or a flat list of ints, each in [0, vertexCount).
std::vector<glm::uvec3> readIndices(const JsonNode& node, size_t vertexCount) {
    node.requireArray();
    std::vector<unsigned> flat;
    auto readIndex = [&](const JsonNode& n) {
        int64_t index = n.integer64();
        if (index < 0 || static_cast<uint64_t>(index) >= vertexCount)
            n.fail(
                fmt::format("vertex index {} is out of range: there are {} positions", index, vertexCount));
        flat.push_back(static_cast<unsigned>(index));
    };
    bool nested = !node.value().empty() && node.value()[0].is_array();
    for (size_t i = 0; i < node.size(); ++i) {
        JsonNode item = node.element(i);
        if (!nested) {
            readIndex(item);
            continue;
        }
        if (!item.value().is_array() || item.size() != 3)
            item.fail("expected a triangle [i, j, k], got " + describeValue(item.value()));
        for (size_t k = 0; k < 3; ++k) readIndex(item.element(k));
    }
    if (flat.size() % 3 != 0)
        node.fail(
            fmt::format("expected a multiple of 3 indices (one triple per triangle), got {}", flat.size()));
    std::vector<glm::uvec3> triangles;
    for (size_t i = 0; i < flat.size(); i += 3) triangles.emplace_back(flat[i], flat[i + 1], flat[i + 2]);
    return triangles;
}

TriangleMesh readTrianglesShape(const JsonNode& node) {
    node.allowKeys({"type", "positions", "indices", "smooth"});
    JsonNode positionsNode = node.child("positions");
    positionsNode.requireArray();
    std::vector<glm::vec3> positions;
    for (size_t i = 0; i < positionsNode.size(); ++i) positions.push_back(positionsNode.element(i).vec3());
    std::vector<glm::uvec3> triangles = readIndices(node.child("indices"), positions.size());
    bool smooth = node.has("smooth") && node.child("smooth").boolean();
    return makeTriangles(positions, triangles, smooth);
}

int readSegments(const JsonNode& node, int fallback) {
    return node.has("segments") ? node.child("segments").integer(3, kMaxShapeSegments) : fallback;
}

TriangleMesh readShape(const JsonNode& node) {
    node.requireObject();
    JsonNode typeNode = node.child("type");
    std::string type = typeNode.string();
    if (type == "box") {
        node.allowKeys({"type", "size"});
        return makeBox(node.child("size").vec3(kPositive));
    }
    if (type == "sphere") {
        node.allowKeys({"type", "radius", "segments"});
        return makeSphere(node.child("radius").floatNumber(kPositive), readSegments(node, 32));
    }
    if (type == "quad") {
        node.allowKeys({"type", "size"});
        JsonNode size = node.child("size");
        if (!size.value().is_array() || size.size() != 2)
            size.fail("expected [width, depth] (2 numbers), got " + describeValue(size.value()));
        return makeQuad({size.element(0).floatNumber(kPositive), size.element(1).floatNumber(kPositive)});
    }
    if (type == "torus") {
        node.allowKeys({"type", "major_radius", "minor_radius", "segments"});
        float major = node.child("major_radius").floatNumber(kPositive);
        JsonNode minorNode = node.child("minor_radius");
        float minor = minorNode.floatNumber(kPositive);
        if (minor >= major)
            minorNode.fail(fmt::format("expected less than major_radius ({}), got {}", major, minor));
        return makeTorus(major, minor, readSegments(node, 48));
    }
    if (type == "triangles") return readTrianglesShape(node);
    typeNode.fail("expected \"box\", \"sphere\", \"quad\", \"torus\" or \"triangles\", got \"" + type + "\"");
}

// The virtual objects' "keyframes" (null for the real scene's entries, which cannot move).
struct KeyframeReader {
    const Scene& scene;  // its sequence and frame rate
    std::vector<ObjectAnimation>& animations;
};

// A texture key: a file relative to the scene file, read once per scene (and encoding).
TextureSlot readTextureFile(const JsonNode& node, TextureEncoding encoding, MeshInputs& inputs) {
    const fs::path file = inputFile(node, inputs.sceneFolder);
    TextureSlot slot;
    slot.texture = inputs.textures.load(file, encoding, node.where());
    return slot;
}

// Keeps each mesh's object-space copy when `movable` (the virtual objects, which setTransform() moves).
std::vector<TriangleMesh> readMeshEntry(const JsonNode& entry, MeshInputs& inputs, bool movable,
                                        std::optional<ObjectAnimation>& animation,
                                        const KeyframeReader* keyframes) {
    entry.allowKeys({"name", "file", "shape", "transform", "material", "keyframes"});
    auto fileNode = entry.find("file"), shapeNode = entry.find("shape");
    if (fileNode && shapeNode) shapeNode->fail("give either \"file\" or \"shape\", not both");
    if (!fileNode && !shapeNode) entry.fail("expected a \"file\" or a \"shape\"");
    if (auto n = entry.find("keyframes")) {
        if (!keyframes) n->fail("only virtual objects move (the real scene is what the photos show)");
        if (entry.has("transform"))
            n->fail("give either \"transform\" or \"keyframes\" (each keyframe gives the pose), not both");
        if (keyframes->scene.sequence.empty())
            n->fail("keyframes need a \"sequence\": their frames are the sequence's");
        animation = readKeyframes(*n, keyframes->scene.frameRate);
    }
    std::optional<std::string> name;
    if (auto n = entry.find("name")) name = n->string();
    glm::mat4 worldFromObject =
        entry.has("transform") ? readTransform(entry.child("transform")) : glm::mat4(1.0f);
    auto materialNode = entry.find("material");
    const TextureReader readTexture = [&](const JsonNode& node, TextureEncoding encoding) {
        return readTextureFile(node, encoding, inputs);
    };
    MaterialOverrides overrides =
        materialNode ? readMaterial(*materialNode, readTexture, inputs.warnings) : MaterialOverrides{};
    std::string materialWhere = materialNode ? materialNode->where() : entry.where();

    std::vector<FileMesh> meshes;
    if (fileNode) {
        fs::path path = inputFile(*fileNode, inputs.sceneFolder);
        inputs.files.push_back(path);
        meshes = loadMeshFile(path, fileNode->where(), name.value_or(path.stem().string()), &inputs.warnings);
    } else {
        meshes.push_back({readShape(*shapeNode), {}});
        meshes.back().mesh.name = name.value_or(shapeNode->child("type").string());
    }
    std::vector<TriangleMesh> result;
    for (FileMesh& fileMesh : meshes) {
        TriangleMesh& mesh = fileMesh.mesh;
        mesh.material = combineMaterial(overrides, fileMesh.material, mesh.name, materialWhere);
        dropUnusableTextures(mesh.material, mesh, materialWhere, inputs.warnings);
        if (movable) {
            mesh.objectSpace = std::make_shared<const TriangleMesh>(mesh);
            mesh.worldFromObject = worldFromObject;
        }
        transformMesh(mesh, worldFromObject);
        cleanMesh(mesh, entry.where());
        result.push_back(std::move(mesh));
    }
    return result;
}

// Appends the mesh files it reads to `inputs.files`, its warnings to `inputs.warnings`, and the entries'
// keyframes to `keyframes->animations`. `entries`, when given, gets each mesh's entry index.
std::vector<TriangleMesh> readMeshList(const JsonNode& list, MeshInputs& inputs, bool movable,
                                       const KeyframeReader* keyframes = nullptr,
                                       std::vector<int>* entries = nullptr) {
    list.requireArray();
    std::vector<TriangleMesh> meshes;
    for (size_t i = 0; i < list.size(); ++i) {
        std::optional<ObjectAnimation> animation;
        std::vector<TriangleMesh> entry =
            readMeshEntry(list.element(i), inputs, movable, animation, keyframes);
        if (animation) {
            animation->firstMesh = meshes.size();
            animation->meshCount = entry.size();
            keyframes->animations.push_back(std::move(*animation));
        }
        if (entries) entries->insert(entries->end(), entry.size(), static_cast<int>(i));
        for (const TriangleMesh& mesh : entry) inputs.triangles += mesh.triangleCount();
        if (inputs.checkMemory) inputs.checkMemory(inputs.triangles, list.element(i).where());
        std::move(entry.begin(), entry.end(), std::back_inserter(meshes));
    }
    return meshes;
}

// ---- albedo from the photo --------------------------------------------------------------------------------

// The "albedo" key of entry `index` of `list` when it is "estimate".
std::optional<JsonNode> estimateKey(const JsonNode& list, size_t index) {
    const JsonNode entry = list.element(index);
    if (!entry.value().is_object()) return std::nullopt;
    auto material = entry.find("material");
    if (!material || !material->value().is_object()) return std::nullopt;
    auto albedo = material->find("albedo");
    if (!albedo || !asksForEstimate(albedo->value())) return std::nullopt;
    return albedo;
}

// Which entries of "scene" ask for "albedo": "estimate" (checked before the meshes load: only real meshes,
// and only with a photo).
std::vector<bool> albedoRequests(const JsonNode& root, const Scene& scene) {
    if (auto list = root.find("virtual"); list && list->value().is_array())
        for (size_t i = 0; i < list->size(); ++i)
            if (auto key = estimateKey(*list, i))
                key->fail(
                    "\"estimate\" is for the real scene's meshes (\"scene\"): the photo does not show the "
                    "virtual objects");
    std::vector<bool> requests;
    auto list = root.find("scene");
    if (!list || !list->value().is_array()) return requests;
    for (size_t i = 0; i < list->size(); ++i) {
        auto key = estimateKey(*list, i);
        requests.push_back(key.has_value());
        if (key && !scene.background)
            key->fail("\"estimate\" takes the albedo from the photo, and the scene has no \"background\"");
    }
    return requests;
}

// Per real mesh, whether its entry asked for an estimate (`requests`: per entry of "scene").
std::vector<bool> realMeshRequests(const std::vector<bool>& requests, const Scene& scene) {
    std::vector<bool> meshes(scene.real.size(), false);
    for (size_t m = 0; m < scene.real.size(); ++m)
        meshes[m] = requests.at(static_cast<size_t>(scene.realEntries.at(m)));
    return meshes;
}

// ---- the document -----------------------------------------------------------------------------------------

void readBackground(const JsonNode& node, const fs::path& sceneFolder, Scene& scene) {
    scene.backgroundFile = inputFile(node, sceneFolder);
    const Camera& camera = scene.camera;
    const auto wrongSize = [&](int width, int height) {
        node.fail(fmt::format("expected an image of the camera's size {}, got {} ('{}')",
                              sizeText(camera.width, camera.height), sizeText(width, height),
                              scene.backgroundFile.string()));
    };
    // By its header first: a photo of another size is not decoded.
    if (const auto size = imageFileSize(scene.backgroundFile);
        size && (size->first != camera.width || size->second != camera.height))
        wrongSize(size->first, size->second);
    try {
        scene.background = readImage(scene.backgroundFile);
    } catch (const InputError& e) {
        node.fail(e.what());
    }
    if (scene.background->width() != camera.width || scene.background->height() != camera.height)
        wrongSize(scene.background->width(), scene.background->height());
}

// "sequence": {"transforms": FILE, "frames": "A:B", "fps": N}: the frames' cameras and photos; the first
// frame's camera and photo are the scene's.
void readSequence(const JsonNode& node, const fs::path& sceneFolder, Scene& scene) {
    node.allowKeys({"transforms", "frames", "fps"});
    scene.sequenceFile = inputFile(node.child("transforms"), sceneFolder);
    FrameRange range;
    if (auto n = node.find("frames")) range = parseFrameRange(n->string(), n->where());
    scene.sequence = readTransforms(scene.sequenceFile, range);
    if (auto n = node.find("fps"))
        scene.frameRate = n->number({0.0, kMaxFrameRate, true, false});
    else if (auto fps = transformsFrameRate(scene.sequenceFile))
        scene.frameRate = *fps;
    // The first frame's camera and photo (the keyframed objects are posed once they are read).
    showFrame(scene, scene.sequence.front());
}

bool holdsEntries(const JsonNode& root, std::string_view key) {
    auto node = root.find(key);
    if (!node) return false;
    node->requireArray();
    return node->size() > 0;
}

// ---- warnings -------------------------------------------------------------------------------------------

// Whether `point` is inside the closed surface of `mesh`: a ray from it crosses the surface an odd number of
// times. Three rays vote, so that a ray through an edge (counted twice or not at all) cannot decide alone.
bool encloses(const TriangleMesh& mesh, glm::vec3 point) {
    if (!mesh.bounds().contains(point)) return false;
    static const glm::dvec3 kDirections[] = {glm::normalize(glm::dvec3(0.5377, 0.8173, 0.2071)),
                                             glm::normalize(glm::dvec3(-0.6713, 0.1543, -0.7249)),
                                             glm::normalize(glm::dvec3(0.1139, -0.9023, 0.4157))};
    int insideVotes = 0;
    for (const glm::dvec3& direction : kDirections) {
        size_t crossings = 0;
        for (glm::uvec3 t : mesh.triangles) {
            // Moller-Trumbore, in double.
            const glm::dvec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
            const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(direction, e2);
            const double det = glm::dot(e1, p);
            if (det == 0.0) continue;
            const glm::dvec3 s = glm::dvec3(point) - a;
            const double u = glm::dot(s, p) / det;
            if (u < 0.0 || u > 1.0) continue;
            const glm::dvec3 q = glm::cross(s, e1);
            const double v = glm::dot(direction, q) / det;
            if (v < 0.0 || u + v > 1.0) continue;
            if (glm::dot(e2, q) / det > 0.0) ++crossings;
        }
        insideVotes += crossings % 2 == 1;
    }
    return insideVotes >= 2;
}

// What renders, but probably not as meant: no light at all, a virtual object around the camera, a virtual
// object outside the voxel volume (no indirect light for it, none from it).
// Positions farther out than kMaxCoordinate: a float has no precision left there for a ray to start or end
// by a surface, and Embree's ray checks fail (a camera at 5e18 aborted inside it).
constexpr float kMaxCoordinate = 1e8f;

bool farOut(const glm::vec3& p) {
    return !(std::abs(p.x) <= kMaxCoordinate && std::abs(p.y) <= kMaxCoordinate &&
             std::abs(p.z) <= kMaxCoordinate);
}

std::string pointText(const glm::vec3& p) {
    return fmt::format("({:.4g}, {:.4g}, {:.4g})", p.x, p.y, p.z);
}

void checkCoordinates(const Scene& scene, const std::string& file) {
    const auto fail = [&](const std::string& where, const glm::vec3& p) {
        throw InputError(
            file + ": " + where,
            fmt::format("at {}: farther out than {:g} world units on an axis, where a 32-bit float "
                        "cannot place a ray by a surface",
                        pointText(p), kMaxCoordinate));
    };
    if (farOut(scene.camera.position())) fail("camera", scene.camera.position());
    for (const SequenceFrame& frame : scene.sequence)
        if (farOut(frame.camera.position()))
            fail(frame.photo.empty()
                     ? fmt::format("sequence: frame {}", frame.index)
                     : fmt::format("sequence: frame {} ({})", frame.index, frame.photo.filename().string()),
                 frame.camera.position());
    for (size_t i = 0; i < scene.lights.size(); ++i)
        if (scene.lights[i].type != Light::Type::Directional && farOut(scene.lights[i].position))
            fail(fmt::format("lights[{}].position", i), scene.lights[i].position);
    for (const auto& [meshes, key] : {std::pair{&scene.real, "scene"}, std::pair{&scene.virtuals, "virtual"}})
        for (const TriangleMesh& mesh : *meshes) {
            const Bounds3f b = mesh.bounds();
            for (const glm::vec3& corner : {b.min, b.max})
                if (farOut(corner)) fail(fmt::format("{}: mesh '{}'", key, mesh.name), corner);
        }
}

std::vector<std::string> sceneWarnings(const Scene& scene) {
    std::vector<std::string> warnings;
    bool lit = scene.environment.has_value();
    for (const Light& light : scene.lights) lit = lit || light.power() != glm::vec3(0.0f);
    for (const auto* meshes : {&scene.real, &scene.virtuals})
        for (const TriangleMesh& mesh : *meshes) lit = lit || mesh.material.emits();
    if (!lit)
        warnings.push_back(
            "lights: the scene has no light (no \"lights\" with a non-zero intensity, no \"environment\", no "
            "emitting surface): the virtual objects will be black");
    const glm::vec3 camera = scene.camera.position();
    for (const TriangleMesh& mesh : scene.virtuals)
        if (encloses(mesh, camera))
            warnings.push_back(
                fmt::format("virtual: mesh '{}' encloses the camera (at ({:.4g}, {:.4g}, {:.4g})): the "
                            "camera sees only its "
                            "inside",
                            mesh.name, camera.x, camera.y, camera.z));
    if (scene.virtuals.empty()) return warnings;
    const Bounds3f volume = volumeRegion(scene).bounds();
    for (const TriangleMesh& mesh : scene.virtuals) {
        const Bounds3f bounds = mesh.bounds();
        bool inside = true, overlaps = true;
        for (int a = 0; a < 3; ++a) {
            inside = inside && bounds.min[a] >= volume.min[a] && bounds.max[a] <= volume.max[a];
            overlaps = overlaps && bounds.max[a] >= volume.min[a] && bounds.min[a] <= volume.max[a];
        }
        if (inside) continue;
        warnings.push_back(
            fmt::format("virtual: mesh '{}' {} the voxel volume (from ({:.4g}, {:.4g}, {:.4g}) to ({:.4g}, "
                        "{:.4g}, {:.4g}); "
                        "options.volume): {}",
                        mesh.name, overlaps ? "extends beyond" : "lies outside", volume.min.x, volume.min.y,
                        volume.min.z, volume.max.x, volume.max.y, volume.max.z,
                        overlaps ? "its part outside neither gets nor gives indirect light"
                                 : "it neither gets nor gives indirect light"));
    }
    return warnings;
}

}  // namespace

SceneRead readScene(const json& document, const fs::path& file) {
    JsonNode root(document, file.string());
    if (!document.is_object())
        root.fail("expected a JSON object {...} at the top level, got " + describeValue(document));
    root.allowKeys({"description", "camera", "sequence", "background", "environment", "scene", "virtual",
                    "lights", "markers", "options"});
    if (auto n = root.find("description")) n->string();
    fs::path sceneFolder = file.parent_path();

    // Cheap checks first, so that a typo in the options does not wait for a large mesh to load.
    Scene scene;
    scene.file = file;
    if (auto n = root.find("sequence")) {
        if (root.has("camera")) n->fail("give either \"camera\" or \"sequence\" (whose frames have cameras)");
        if (root.has("background"))
            n->fail("give either \"background\" or \"sequence\" (whose frames have photos)");
        readSequence(*n, sceneFolder, scene);
    } else {
        scene.camera = readCamera(root.child("camera"));
    }
    if (auto n = root.find("options")) scene.options = readOptions(*n);
    if (!scene.sequence.empty() && !scene.options.volume.viewpoint)
        scene.options.volume.viewpoint = sequenceViewpoint(scene.sequenceFile);
    if (auto n = root.find("lights")) {
        n->requireArray();
        for (size_t i = 0; i < n->size(); ++i) scene.lights.push_back(readLight(n->element(i)));
    }
    if (auto n = root.find("markers")) {
        n->requireArray();
        for (size_t i = 0; i < n->size(); ++i) {
            const Marker marker = readMarker(n->element(i));
            for (const Marker& other : scene.markers)
                if (other.id == marker.id)
                    n->element(i).child("id").fail(fmt::format("marker {} is listed twice", marker.id));
            scene.markers.push_back(marker);
        }
    }
    const size_t environmentLights = root.has("environment") ? scene.options.environment.lightCount : 0;
    const size_t directional =
        static_cast<size_t>(std::count_if(scene.lights.begin(), scene.lights.end(),
                                          [](const Light& l) { return l.type == Light::Type::Directional; }));
    const size_t pointLights = scene.lights.size() - directional;
    checkRenderMemory(scene.options, scene.camera, pointLights, physicalMemoryBytes(), file.string(),
                      directional + environmentLights);
    if (!holdsEntries(root, "scene") && !holdsEntries(root, "virtual"))
        root.fail("no meshes: at least one of \"scene\" (the real scene) and \"virtual\" must hold a mesh");

    if (auto n = root.find("background")) readBackground(*n, sceneFolder, scene);
    if (auto n = root.find("environment")) readEnvironment(*n, sceneFolder, scene);
    MeshInputs meshInputs{sceneFolder, scene.meshFiles, scene.warnings, {}, {}};
    // Checked again as the meshes come: their triangles count too (a shape's segments, a file's faces).
    meshInputs.checkMemory = [&](uint64_t triangles, const std::string& where) {
        checkRenderMemory(scene.options, scene.camera, pointLights, physicalMemoryBytes(), where,
                          directional + environmentLights, triangles);
    };
    const std::vector<bool> albedoEstimates = albedoRequests(root, scene);
    if (auto n = root.find("scene"))
        scene.real = readMeshList(*n, meshInputs, false, nullptr, &scene.realEntries);
    if (auto n = root.find("virtual")) {
        const KeyframeReader keyframes{scene, scene.animations};
        scene.virtuals = readMeshList(*n, meshInputs, true, &keyframes, &scene.virtualEntries);
    }
    // Moving objects: placed for the first frame, in a volume region that holds them in every frame.
    if (!scene.animations.empty()) {
        poseObjects(scene, scene.sequence.front().index);
        fixVolumeRegionOverAnimation(scene);
    }
    checkCoordinates(scene, file.string());
    for (const std::string& warning : lightPlacementWarnings(scene))
        scene.warnings.push_back(file.string() + ": " + warning);
    for (const std::string& warning : sceneWarnings(scene))
        scene.warnings.push_back(file.string() + ": " + warning);
    std::vector<bool> estimate = realMeshRequests(albedoEstimates, scene);
    return SceneRead{std::move(scene), std::move(estimate)};
}

json readSceneDocument(const fs::path& file, const std::vector<std::string>& overrides) {
    // Checked before it is opened: opening a FIFO waits for a writer.
    std::error_code error;
    const fs::file_status status = fs::status(file, error);
    if (fs::exists(status) && !fs::is_regular_file(status))
        throw InputError(file.string(),
                         "cannot open scene file: not a regular file (a folder, a FIFO, a device)");
    if (error && error != std::errc::no_such_file_or_directory)
        throw InputError(file.string(), "cannot open scene file: " + error.message());
    std::ifstream in(file, std::ios::binary);
    if (!fs::is_regular_file(status) || !in) throw InputError(file.string(), "cannot open scene file");
    std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    json document = parseJson(text, file.string());
    for (const std::string& override : overrides) applyOverride(document, override);
    return document;
}

SceneRead readScene(const fs::path& file, const std::vector<std::string>& overrides) {
    return readScene(readSceneDocument(file, overrides), file);
}

void applyOverride(json& document, const std::string& keyEqualsValue) {
    size_t equals = keyEqualsValue.find('=');
    if (equals == std::string::npos)
        throw InputError("--set " + keyEqualsValue, "expected KEY=VALUE, e.g. options.volume.resolution=64");
    std::string key = keyEqualsValue.substr(0, equals), valueText = keyEqualsValue.substr(equals + 1);
    std::string where = "--set " + key;
    json value;
    try {
        value = parseJson(valueText, where);
    } catch (const InputError&) {
        value = valueText;  // not JSON (or too deep, or with a repeated key): a string
    }

    json* node = &document;
    std::string walked;  // the path so far, for messages
    size_t start = 0;
    while (true) {
        size_t dot = key.find('.', start);
        std::string part = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
        if (part.empty())
            throw InputError(where, "expected KEY as dotted names, e.g. options.volume.resolution");
        if (node->is_null()) *node = json::object();
        if (node->is_object()) {
            node = &(*node)[part];
        } else if (node->is_array()) {
            bool isIndex = part.size() <= 9 && part.find_first_not_of("0123456789") == std::string::npos;
            if (!isIndex)
                throw InputError(where,
                                 fmt::format("'{}' is an array: expected an index, got '{}'", walked, part));
            size_t index = std::stoul(part);
            if (index >= node->size())
                throw InputError(where, fmt::format("index {} is out of range: '{}' has {} element{}", index,
                                                    walked, node->size(), node->size() == 1 ? "" : "s"));
            node = &(*node)[index];
        } else {
            throw InputError(where, fmt::format("cannot set '{}' inside '{}', which is {}", part, walked,
                                                describeValue(*node)));
        }
        walked += (walked.empty() ? "" : ".") + part;
        if (dot == std::string::npos) break;
        start = dot + 1;
    }
    *node = std::move(value);
}

}  // namespace deltagi
