// Scene files: good scenes load with the documented conventions, and every kind of bad input raises an
// InputError naming the file and the JSON path of the key.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>

#include <gtest/gtest.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "scene/json_reader.h"
#include "scene/option_table.h"
#include "test_errors.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Each test gets its own folder (tests may run in parallel processes).
class SceneIoTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ =
            fs::temp_directory_path() / ("deltagi_scene_io_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path write(const std::string& name, const std::string& text) {
        fs::path path = dir_ / name;
        fs::create_directories(path.parent_path());
        std::ofstream(path, std::ios::binary) << text;
        return path;
    }
    fs::path writeScene(const json& document, const std::string& name = "scene.json") {
        return write(name, document.dump(2));
    }
    Scene load(const json& document) { return loadScene(writeScene(document)); }

    // The message of the InputError that `load(document)` raises; fails the test when there is none.
    std::string errorOf(const std::function<void()>& action) {
        try {
            action();
        } catch (const InputError& e) {
            std::string message = e.what();
            EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
            return message;
        }
        ADD_FAILURE() << "expected an InputError";
        return {};
    }
    std::string loadError(const json& document) {
        return errorOf([&] { load(document); });
    }

    fs::path dir_;
};

using test::expectContains;

// A small valid scene: a floor quad (real), a unit box (virtual), one point light.
json baseScene() {
    return json::parse(R"({
        "description": "test scene",
        "camera": {"width": 64, "height": 48, "fov_y_deg": 60, "position": [0, 1, 5], "look_at": [0, 0, 0]},
        "scene": [{"name": "floor", "shape": {"type": "quad", "size": [10, 10]}}],
        "virtual": [{"shape": {"type": "box", "size": [1, 1, 1]}, "transform": {"translate": [0, 0.5, 0]}}],
        "lights": [{"type": "point", "position": [0, 5, 0], "intensity": 10}]
    })");
}

constexpr float kEps = 1e-5f;

void expectNear(glm::vec3 a, glm::vec3 b, float tolerance = kEps) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

// ---- good scenes ------------------------------------------------------------------------------------------

TEST_F(SceneIoTest, LoadsASmallScene) {
    Scene scene = load(baseScene());
    ASSERT_EQ(scene.real.size(), 1u);
    ASSERT_EQ(scene.virtuals.size(), 1u);
    EXPECT_EQ(scene.real[0].name, "floor");
    EXPECT_EQ(scene.real[0].triangleCount(), 2u);
    EXPECT_EQ(scene.virtuals[0].name, "box");
    EXPECT_EQ(scene.virtuals[0].triangleCount(), 12u);
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].type, Light::Type::Point);
    EXPECT_FLOAT_EQ(scene.lights[0].intensity, 10.0f);
    EXPECT_FALSE(scene.background.has_value());
    EXPECT_EQ(scene.options.volume.resolution, 128);  // defaults where the file sets nothing
    EXPECT_EQ(scene.virtuals[0].material.albedo, glm::vec3(0.8f));
    EXPECT_EQ(scene.virtuals[0].material.specular, glm::vec3(0.0f));
    EXPECT_EQ(scene.virtuals[0].material.roughness, 1.0f);
}

TEST_F(SceneIoTest, LookAtCameraLooksAtTarget) {
    Scene scene = load(baseScene());
    const Camera& camera = scene.camera;
    // fov form: fy = height / 2 / tan(fov / 2), square pixels, centred principal point.
    float expectedFy = 24.0f / std::tan(glm::radians(30.0f));
    EXPECT_NEAR(camera.fy, expectedFy, 1e-4f);
    EXPECT_NEAR(camera.fx, expectedFy, 1e-4f);
    EXPECT_FLOAT_EQ(camera.cx, 32.0f);
    EXPECT_FLOAT_EQ(camera.cy, 24.0f);
    expectNear(camera.position(), {0, 1, 5});
    glm::vec3 forward = glm::normalize(glm::vec3(0, 0, 0) - glm::vec3(0, 1, 5));
    expectNear(glm::normalize(camera.rayDirection(camera.cx, camera.cy)), forward);
    // Image right is world +x here, and image up (smaller pixel y) leans to world +y.
    EXPECT_GT(camera.rayDirection(camera.cx + 10, camera.cy).x, 0.0f);
    EXPECT_GT(camera.rayDirection(camera.cx, camera.cy - 10).y, camera.rayDirection(camera.cx, camera.cy).y);
    // The top edge of the image is fov/2 above the axis.
    glm::vec3 top = glm::normalize(camera.rayDirection(camera.cx, 0.0f));
    EXPECT_NEAR(glm::degrees(std::acos(glm::dot(top, forward))), 30.0f, 1e-3f);
}

TEST_F(SceneIoTest, PinholeIntrinsicsDefaultToCentre) {
    json doc = baseScene();
    doc["camera"] = json::parse(R"({"width": 640, "height": 480, "fx": 500, "fy": 510, "position": [0, 0, 0],
                                    "look_at": [0, 0, -1]})");
    Camera camera = load(doc).camera;
    EXPECT_FLOAT_EQ(camera.fx, 500.0f);
    EXPECT_FLOAT_EQ(camera.fy, 510.0f);
    EXPECT_FLOAT_EQ(camera.cx, 320.0f);
    EXPECT_FLOAT_EQ(camera.cy, 240.0f);
    // Looking down -z with up +y is the identity frame.
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) EXPECT_NEAR(camera.worldFromCamera[c][r], c == r ? 1.0f : 0.0f, kEps);
}

TEST_F(SceneIoTest, WorldFromCameraIsRowMajor) {
    json doc = baseScene();
    // 90 degrees about +y (camera -z turns to world -x), at (1, 2, 3); written as printed, rows first.
    doc["camera"] = json::parse(R"({"width": 64, "height": 48, "fx": 50, "fy": 50, "cx": 30, "cy": 20,
        "world_from_camera": [[0, 0, 1, 1], [0, 1, 0, 2], [-1, 0, 0, 3], [0, 0, 0, 1]]})");
    Camera camera = load(doc).camera;
    EXPECT_FLOAT_EQ(camera.cx, 30.0f);
    expectNear(camera.position(), {1, 2, 3});
    expectNear(glm::normalize(camera.rayDirection(30, 20)), {-1, 0, 0});
    expectNear(camera.worldFromCamera * glm::vec4(1, 0, 0, 0), {0, 0, -1});  // camera right
}

TEST_F(SceneIoTest, TransformsApplyScaleRotateTranslate) {
    json doc = baseScene();
    doc["virtual"][0]["transform"] = json::parse(R"({"translate": [1, 2, 3], "scale": 2})");
    Bounds3f b = load(doc).virtuals[0].bounds();
    expectNear(b.min, {0, 1, 2});
    expectNear(b.max, {2, 3, 4});

    // Rotations about X, then Y, then Z: (0, 1, 0) -> X 90 -> (0, 0, 1) -> Y 90 -> (1, 0, 0).
    doc["virtual"][0] = json::parse(R"({"shape": {"type": "triangles",
        "positions": [[0, 1, 0], [0, 1, 1], [1, 1, 0]], "indices": [0, 1, 2]},
        "transform": {"rotate_deg": [90, 90, 0]}})");
    TriangleMesh tri = load(doc).virtuals[0];
    expectNear(tri.positions[0], {1, 0, 0});

    // A 4x4 row-major matrix: the translation is the last column.
    doc["virtual"][0]["transform"] = json::parse("[[1, 0, 0, 5], [0, 1, 0, 6], [0, 0, 1, 7], [0, 0, 0, 1]]");
    expectNear(load(doc).virtuals[0].positions[0], {5, 7, 7});
}

TEST_F(SceneIoTest, NormalsFollowTheInverseTranspose) {
    json doc = baseScene();
    doc["virtual"][0] = json::parse(R"({"shape": {"type": "sphere", "radius": 1, "segments": 16},
                                        "transform": {"scale": [2, 1, 1]}})");
    TriangleMesh mesh = load(doc).virtuals[0];
    // On the ellipsoid (x/2)^2 + y^2 + z^2 = 1 the normal is the gradient (x/4, y, z).
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        glm::vec3 p = mesh.positions[i];
        expectNear(mesh.normals[i], glm::normalize(glm::vec3(p.x / 4, p.y, p.z)), 1e-4f);
    }
}

TEST_F(SceneIoTest, MirroringKeepsBoxFacesOutward) {
    json doc = baseScene();
    doc["virtual"][0]["transform"] = json::parse(R"({"translate": [0, 0.5, 0], "scale": [-1, 1, 1]})");
    TriangleMesh mesh = load(doc).virtuals[0];
    for (glm::uvec3 t : mesh.triangles) {
        glm::vec3 a = mesh.positions[t.x], b = mesh.positions[t.y], c = mesh.positions[t.z];
        glm::vec3 faceNormal = glm::normalize(glm::cross(b - a, c - a));
        EXPECT_GT(glm::dot(faceNormal, (a + b + c) / 3.0f - glm::vec3(0, 0.5f, 0)), 0.0f);  // outward
        EXPECT_GT(glm::dot(faceNormal, mesh.normals[t.x]), 0.99f);
    }
}

// Two cubes side by side in one OBJ, with two MTL materials.
const char* kTwoCubesObj = R"(mtllib two.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
o left
usemtl red
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
o right
usemtl shiny
f 1 4 3 2
f 5 6 7 8
)";
const char* kTwoCubesMtl = R"(newmtl red
Kd 0.5 0.2 0.1
Ks 0.1 0.1 0.1
Ns 98
newmtl shiny
Kd 0.3 0.3 0.3
Ks 0.6 0.6 0.6
Ns 0
)";

TEST_F(SceneIoTest, MaterialsComeFromMtlAndJsonOverridesKeyByKey) {
    write("meshes/two.obj", kTwoCubesObj);
    write("meshes/two.mtl", kTwoCubesMtl);
    json doc = baseScene();
    doc["virtual"][0] = {{"file", "meshes/two.obj"}};
    Scene scene = load(doc);
    ASSERT_EQ(scene.virtuals.size(), 2u);
    const TriangleMesh* red = nullptr;
    const TriangleMesh* shiny = nullptr;
    for (const TriangleMesh& m : scene.virtuals) {
        EXPECT_EQ(m.name.rfind("two/", 0), 0u) << m.name;  // "<file stem>/<sub-mesh>"
        (m.triangleCount() == 12 ? red : shiny) = &m;
    }
    ASSERT_TRUE(red && shiny);
    EXPECT_EQ(shiny->triangleCount(), 4u);
    expectNear(red->material.albedo, {0.5f, 0.2f, 0.1f});
    expectNear(red->material.specular, glm::vec3(0.1f));
    EXPECT_NEAR(red->material.roughness, std::sqrt(2.0f / 100.0f), 1e-5f);
    expectNear(shiny->material.specular, glm::vec3(0.6f));
    EXPECT_FLOAT_EQ(shiny->material.roughness, 1.0f);  // Ns 0

    // JSON keys override the file's key by key; the others stay.
    doc["virtual"][0]["name"] = "cubes";
    doc["virtual"][0]["material"] = {{"albedo", 0.25}, {"glossiness", 0.75}};
    scene = load(doc);
    for (const TriangleMesh& m : scene.virtuals) {
        EXPECT_EQ(m.name.rfind("cubes/", 0), 0u) << m.name;
        expectNear(m.material.albedo, glm::vec3(0.25f));
        EXPECT_FLOAT_EQ(m.material.roughness, 0.25f);
    }
    expectNear(scene.virtuals[0].material.specular + scene.virtuals[1].material.specular, glm::vec3(0.7f));
}

// Emission: "emission" (radiance) times "emission_scale", or the MTL file's Ke times the scale; no emission
// by default, and "Ke 0 0 0" (what many exporters write) is no emitter.
TEST_F(SceneIoTest, EmissionFromJsonAndMtlTimesTheScale) {
    json doc = baseScene();
    EXPECT_FALSE(load(doc).virtuals[0].material.emits());
    doc["virtual"][0]["material"] = {{"emission", {1, 2, 3}}, {"emission_scale", 0.5}};
    expectNear(load(doc).virtuals[0].material.emission, {0.5f, 1.0f, 1.5f});
    doc["virtual"][0]["material"] = {{"emission", 4}};
    expectNear(load(doc).virtuals[0].material.emission, glm::vec3(4.0f));

    write("lamp.obj", "mtllib lamp.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl light\nf 1 2 3\n");
    write("lamp.mtl", "newmtl light\nKd 0.78 0.78 0.78\nKe 17 12 4\n");
    doc["virtual"][0] = {{"file", "lamp.obj"}, {"material", {{"emission_scale", 0.1}}}};
    expectNear(load(doc).virtuals[0].material.emission, {1.7f, 1.2f, 0.4f});
    write("dark.obj", "mtllib dark.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl dark\nf 1 2 3\n");
    write("dark.mtl", "newmtl dark\nKd 0.5 0.5 0.5\nKe 0 0 0\n");
    doc["virtual"][0] = {{"file", "dark.obj"}};
    EXPECT_FALSE(load(doc).virtuals[0].material.emits());
}

TEST_F(SceneIoTest, BadEmissionIsAnError) {
    json doc = baseScene();
    doc["virtual"][0]["material"] = {{"emission", {1, -2, 3}}};
    expectContains(loadError(doc), {"scene.json: virtual[0].material.emission[1]", "[0, inf)"});
    doc["virtual"][0]["material"] = {{"emission", 1}, {"emission_scale", -1}};
    expectContains(loadError(doc), {"virtual[0].material.emission_scale", "[0, inf)"});
    doc["virtual"][0]["material"] = {{"emission", 1e30}, {"emission_scale", 1e30}};
    expectContains(loadError(doc), {"virtual[0].material.emission_scale", "not a finite number"});
    doc["virtual"][0]["material"] = {{"emision", 1}};
    expectContains(loadError(doc), {"virtual[0].material.emision", "unknown key", "emission_scale"});
}

TEST_F(SceneIoTest, FileWithoutMaterialsGetsDefaults) {
    write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    json doc = baseScene();
    doc["virtual"][0] = {{"file", "tri.obj"}};
    TriangleMesh mesh = load(doc).virtuals[0];
    EXPECT_EQ(mesh.name, "tri");
    EXPECT_EQ(mesh.material.albedo, glm::vec3(0.8f));
    expectNear(mesh.normals[0], {0, 0, 1});
}

// The mesh files read, resolved against the scene's folder (the CLI refuses to write over them).
TEST_F(SceneIoTest, MeshFilesAreListed) {
    write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write("meshes/other.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    json doc = baseScene();
    doc["scene"][1] = {{"file", "meshes/other.obj"}};
    doc["virtual"][0] = {{"file", "tri.obj"}};
    const Scene scene = load(doc);
    ASSERT_EQ(scene.meshFiles.size(), 2u);
    EXPECT_TRUE(fs::equivalent(scene.meshFiles[0], dir_ / "meshes" / "other.obj")) << scene.meshFiles[0];
    EXPECT_TRUE(fs::equivalent(scene.meshFiles[1], dir_ / "tri.obj")) << scene.meshFiles[1];
    EXPECT_TRUE(load(baseScene()).meshFiles.empty());  // shapes only
}

TEST_F(SceneIoTest, EmptyVirtualListAndNoLightsAreFine) {
    json doc = baseScene();
    doc["virtual"] = json::array();
    doc["lights"] = json::array();
    Scene scene = load(doc);
    EXPECT_TRUE(scene.virtuals.empty());
    EXPECT_TRUE(scene.lights.empty());
}

TEST_F(SceneIoTest, LightsReadWithDefaults) {
    json doc = baseScene();
    doc["lights"] = json::parse(R"([
        {"type": "spot", "name": "key", "position": [0, 3, 0], "direction": [0, -2, 0], "color": [1, 0.5, 0.25]},
        {"type": "directional", "direction": [1, -1, 0], "intensity": 3}])");
    Scene scene = load(doc);
    ASSERT_EQ(scene.lights.size(), 2u);
    const Light& spot = scene.lights[0];
    EXPECT_EQ(spot.type, Light::Type::Spot);
    expectNear(spot.direction, {0, -1, 0});
    EXPECT_FLOAT_EQ(spot.innerAngleDeg, 30.0f);
    EXPECT_FLOAT_EQ(spot.outerAngleDeg, 45.0f);
    expectNear(spot.power(), {1, 0.5f, 0.25f});
    expectNear(scene.lights[1].direction, glm::normalize(glm::vec3(1, -1, 0)));
    expectNear(scene.lights[1].power(), glm::vec3(3.0f));
}

TEST_F(SceneIoTest, OptionsReadAndWriteBack) {
    json doc = baseScene();
    doc["options"] = json::parse(R"({"volume": {"resolution": 64, "center": [0, 1, 0], "size": 4},
        "trace": {"accumulation": "paper", "step_scale": 0.25, "jitter": 0},
        "render": {"samples_per_pixel": 9, "indirect": false}})");
    Options options = load(doc).options;
    EXPECT_EQ(options.volume.resolution, 64);
    ASSERT_TRUE(options.volume.center && options.volume.size);
    EXPECT_FLOAT_EQ(*options.volume.size, 4.0f);
    EXPECT_EQ(options.trace.accumulation, ConeAccumulation::Paper);
    EXPECT_EQ(options.trace.jitter, 0.0f);
    EXPECT_EQ(options.render.samplesPerPixel, 9);
    EXPECT_FALSE(options.render.indirect);

    json written = optionsToJson(options);
    EXPECT_EQ(written["volume"]["resolution"], 64);
    EXPECT_EQ(written["trace"]["step_scale"], 0.25);
    EXPECT_EQ(written["diffuse"]["count"], 9);  // a default
    // What optionsToJson writes reads back to the same options, defaults (null region) included.
    for (const Options& original : {options, Options{}}) {
        Options again = readOptions(JsonNode(optionsToJson(original), "written"));
        EXPECT_EQ(optionsToJson(again), optionsToJson(original));
    }
}

TEST_F(SceneIoTest, BackgroundIsLoadedAndResolvedRelativeToTheSceneFile) {
    Image photo(64, 48, 3, 0.5f);
    fs::create_directories(dir_ / "photos");
    writeImage(photo, dir_ / "photos" / "bg.exr");
    json doc = baseScene();
    doc["background"] = "photos/bg.exr";
    Scene scene = load(doc);
    ASSERT_TRUE(scene.background.has_value());
    EXPECT_EQ(scene.background->width(), 64);
    EXPECT_FLOAT_EQ(scene.background->at(3, 4, 1), 0.5f);
    EXPECT_EQ(scene.backgroundFile, dir_ / "photos" / "bg.exr");
}

// ---- overrides --------------------------------------------------------------------------------------------

TEST(ApplyOverrideTest, SetsCreatesAndIndexes) {
    json doc = baseScene();
    applyOverride(doc, "options.volume.resolution=64");
    EXPECT_EQ(doc["options"]["volume"]["resolution"], 64);
    applyOverride(doc, "virtual.0.material.albedo=[0.1, 0.2, 0.3]");
    EXPECT_EQ(doc["virtual"][0]["material"]["albedo"], json::parse("[0.1, 0.2, 0.3]"));
    applyOverride(doc, "options.trace.accumulation=front_to_back");  // not JSON: a string
    EXPECT_EQ(doc["options"]["trace"]["accumulation"], "front_to_back");
    applyOverride(doc, "options.render.indirect=false");
    EXPECT_EQ(doc["options"]["render"]["indirect"], false);
    applyOverride(doc, "description=a=b");  // only the first '=' splits
    EXPECT_EQ(doc["description"], "a=b");
}

TEST(ApplyOverrideTest, RejectsBadOverrides) {
    json doc = baseScene();
    auto message = [&](const std::string& arg) {
        try {
            applyOverride(doc, arg);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        ADD_FAILURE() << "no error for " << arg;
        return std::string();
    };
    expectContains(message("options.volume.resolution"), {"--set options.volume.resolution", "KEY=VALUE"});
    expectContains(message("virtual.3.name=x"), {"--set virtual.3.name", "out of range", "1 element"});
    expectContains(message("camera.width.x=1"), {"--set camera.width.x", "camera.width"});
    expectContains(message("virtual.first.name=x"), {"--set virtual.first.name", "index"});
}

TEST_F(SceneIoTest, OverridesApplyBeforeValidation) {
    fs::path file = writeScene(baseScene());
    Scene scene = loadScene(file, {"options.volume.resolution=32", "lights.0.intensity=2"});
    EXPECT_EQ(scene.options.volume.resolution, 32);
    EXPECT_FLOAT_EQ(scene.lights[0].intensity, 2.0f);
    std::string message = errorOf([&] { loadScene(file, {"options.volume.resolutoin=32"}); });
    expectContains(message, {"scene.json", "options.volume.resolutoin", "unknown key"});
}

// ---- bad input --------------------------------------------------------------------------------------------

TEST_F(SceneIoTest, MissingAndMalformedFiles) {
    expectContains(errorOf([&] { loadScene(dir_ / "nope.json"); }), {"nope.json", "cannot open scene file"});

    fs::path file = write("broken.json", "{\n  \"camera\": {},\n  \"scene\": [,]\n}\n");
    expectContains(errorOf([&] { loadScene(file); }), {"broken.json: line 3, column"});

    json doc = baseScene();
    doc["virtual"][0] = {{"file", "meshes/missing.obj"}};
    expectContains(loadError(doc), {"scene.json: virtual[0].file", "missing.obj", "not found"});
    EXPECT_EQ(loadError(doc).find("shared data set"), std::string::npos);
    doc["virtual"][0] = {{"file", "../shared/data/meshes/not-there.obj"}};
    expectContains(loadError(doc), {"virtual[0].file", "not-there.obj", "../shared/data", "shared data set"});
}

TEST_F(SceneIoTest, WrongTypesNameThePathAndTheExpectedType) {
    struct Case {
        const char* key;
        json value;
        const char* expected;
    };
    const Case cases[] = {
        {"/options/volume/resolution", "64", "expected an integer"},
        {"/options/volume/resolution", 64.5, "expected an integer"},
        {"/options/volume/resolution", 64.0, "expected an integer"},
        {"/options/trace/step_scale", true, "expected a number"},
        {"/options/render/indirect", 1, "expected true or false"},
        {"/camera/position", json::parse("[0, 1]"), "expected an array of 3 numbers"},
        {"/lights/0/position/1", "up", "expected a number"},
        {"/virtual/0/shape/size/2", 1e300, "expected a finite number"},
        {"/scene", json::object(), "expected an array"},
    };
    for (const Case& c : cases) {
        json doc = baseScene();
        doc[json::json_pointer(c.key)] = c.value;
        std::string path = std::string(c.key).substr(1);
        // "/lights/0/position/1" -> "lights[0].position[1]"
        std::string expectedPath;
        for (size_t start = 0; start < path.size();) {
            size_t slash = std::min(path.find('/', start), path.size());
            std::string part = path.substr(start, slash - start);
            bool index = std::isdigit(static_cast<unsigned char>(part[0]));
            expectedPath += index ? "[" + part + "]" : (expectedPath.empty() ? "" : ".") + part;
            start = slash + 1;
        }
        expectContains(loadError(doc), {"scene.json: " + expectedPath + ":", c.expected});
    }
}

// The options of shadow rays, area lights, further bounces, the relit cones and the region's reach: read,
// written back, and bad values refused naming the key.
TEST_F(SceneIoTest, RayBounceAndReachOptionsAreReadAndChecked) {
    json doc = baseScene();
    doc["options"] = json::parse(R"({"shadow": {"method": "cones", "ray_samples": 9, "area_ray_samples": 25},
        "render": {"light_bounces": 4, "relight_cones": "differential", "relight_object_light": "rays"},
        "diffuse": {"object_rays": 4}, "volume": {"reach_scale": 0}})");
    const Options options = load(doc).options;
    EXPECT_EQ(options.render.relightObjectLight, RelightObjectLight::Rays);
    EXPECT_EQ(options.diffuse.objectRays, 4);
    EXPECT_EQ(options.shadow.method, ShadowMethod::Cones);
    EXPECT_EQ(options.shadow.raySamples, 9);
    EXPECT_EQ(options.shadow.areaRaySamples, 25);
    EXPECT_EQ(options.render.lightBounces, 4);
    EXPECT_EQ(options.render.relightCones, RelightCones::Differential);
    EXPECT_EQ(options.volume.reachScale, 0.0f);
    const json written = optionsToJson(options);
    EXPECT_EQ(written["shadow"]["method"], "cones");
    EXPECT_EQ(written["render"]["light_bounces"], 4);
    EXPECT_EQ(written["volume"]["reach_scale"], 0.0);
    EXPECT_EQ(written["render"]["relight_object_light"], "rays");
    EXPECT_EQ(written["diffuse"]["object_rays"], 4);
    const Options defaults;
    EXPECT_EQ(defaults.render.relightObjectLight, RelightObjectLight::Rays);
    EXPECT_EQ(defaults.diffuse.objectRays, 16);
    EXPECT_EQ(defaults.shadow.method, ShadowMethod::Rays);
    EXPECT_EQ(defaults.render.relightCones, RelightCones::Differential);
    struct Bad {
        const char* options;
        const char* key;
    };
    for (const Bad& bad :
         {Bad{R"({"shadow": {"method": "beams"}})", "options.shadow.method"},
          Bad{R"({"shadow": {"ray_samples": 0}})", "options.shadow.ray_samples"},
          Bad{R"({"shadow": {"area_ray_samples": 1000}})", "options.shadow.area_ray_samples"},
          Bad{R"({"render": {"light_bounces": 0}})", "options.render.light_bounces"},
          Bad{R"({"render": {"relight_cones": true}})", "options.render.relight_cones"},
          Bad{R"({"render": {"relight_object_light": "beams"}})", "options.render.relight_object_light"},
          Bad{R"({"diffuse": {"object_rays": 257}})", "options.diffuse.object_rays"},
          Bad{R"({"volume": {"reach_scale": -1}})", "options.volume.reach_scale"}}) {
        doc["options"] = json::parse(bad.options);
        expectContains(loadError(doc), {std::string("scene.json: ") + bad.key});
    }
}

// options.render.temporal_frames: 4 by default, 1 to 8, written back; anything else refused naming the key.
TEST_F(SceneIoTest, TemporalFramesAreReadAndChecked) {
    json doc = baseScene();
    EXPECT_EQ(load(doc).options.render.temporalFrames, 4);
    doc["options"] = json::parse(R"({"render": {"temporal_frames": 1}})");
    const Options options = load(doc).options;
    EXPECT_EQ(options.render.temporalFrames, 1);
    EXPECT_EQ(optionsToJson(options)["render"]["temporal_frames"], 1);
    for (const char* bad : {"0", "9", "2.5", "\"all\"", "true"}) {
        doc["options"] = json::parse(std::string(R"({"render": {"temporal_frames": )") + bad + "}}");
        expectContains(loadError(doc), {"scene.json: options.render.temporal_frames"});
    }
}

// Pixel strides: "auto" (the default, 0) scales the 640x480 strides with the image; explicit ones are powers
// of two up to 32 and are used as given.
TEST_F(SceneIoTest, RsmResolutionIsAutoOrAnInteger) {
    json doc = baseScene();
    EXPECT_EQ(load(doc).options.rsm.resolution, 0);
    EXPECT_EQ(optionsToJson(Options{})["rsm"]["resolution"], "auto");
    doc["options"] = json::parse(R"({"rsm": {"resolution": 300}})");
    EXPECT_EQ(load(doc).options.rsm.resolution, 300);
    doc["options"] = json::parse(R"({"rsm": {"resolution": "auto"}})");
    EXPECT_EQ(load(doc).options.rsm.resolution, 0);
    for (const char* bad : {"8", "9000", "\"fine\"", "true"}) {
        doc["options"] = json::parse(std::string(R"({"rsm": {"resolution": )") + bad + "}}");
        expectContains(loadError(doc), {"scene.json: options.rsm.resolution"});
    }
}

TEST_F(SceneIoTest, PixelStridesAreAutoOrPowersOfTwo) {
    json doc = baseScene();
    doc["options"] = json::parse(R"({"diffuse": {"pixel_stride": 2, "relight_pixel_stride": "auto"},
        "shadow": {"pixel_stride": 1, "relight_pixel_stride": 32}, "specular": {"relight_pixel_stride": 8}})");
    const Options options = load(doc).options;
    EXPECT_EQ(options.diffuse.pixelStride, 2);
    EXPECT_EQ(options.diffuse.relightPixelStride, 0);
    EXPECT_EQ(options.shadow.pixelStride, 1);
    EXPECT_EQ(options.shadow.relightPixelStride, 32);
    EXPECT_EQ(options.specular.relightPixelStride, 8);
    EXPECT_EQ(optionsToJson(options)["diffuse"]["relight_pixel_stride"], "auto");
    EXPECT_EQ(optionsToJson(Options{})["shadow"]["pixel_stride"], "auto");
    for (const char* bad : {"3", "0", "64", "-2", "\"fast\"", "2.0", "true"}) {
        doc["options"] = json::parse(std::string(R"({"shadow": {"relight_pixel_stride": )") + bad + "}}");
        expectContains(loadError(doc), {"scene.json: options.shadow.relight_pixel_stride"});
    }
    EXPECT_EQ(pixelStrideFor(0, kAutoDiffuseStride, 640, 480), 8);
    EXPECT_EQ(pixelStrideFor(0, kAutoRelightDiffuseStride, 640, 480), 16);
    EXPECT_EQ(pixelStrideFor(0, kAutoShadowStride, 640, 480), 1);
    EXPECT_EQ(pixelStrideFor(0, kAutoRelightShadowStride, 640, 480), 2);
    EXPECT_EQ(pixelStrideFor(0, kAutoRelightAreaLightStride, 640, 480), 2);
    EXPECT_EQ(pixelStrideFor(0, kAutoRelightDiffuseStride, 1920, 1080), 32);  // 16 * 1080/480 = 36 -> 32
    EXPECT_EQ(pixelStrideFor(0, kAutoDiffuseStride, 320, 240), 4);
    EXPECT_EQ(pixelStrideFor(0, kAutoShadowStride, 64, 48), 1);
    EXPECT_EQ(pixelStrideFor(4, kAutoDiffuseStride, 64, 48), 4);  // explicit: as given
}

TEST_F(SceneIoTest, UnknownKeysAreErrors) {
    json doc = baseScene();
    doc["lightz"] = json::array();
    expectContains(loadError(doc), {"scene.json: lightz", "unknown key"});
    doc = baseScene();
    doc["virtual"][0]["material"] = {{"albdo", 0.5}};
    expectContains(loadError(doc), {"scene.json: virtual[0].material.albdo", "unknown key", "albedo"});
    doc = baseScene();
    doc["lights"][0]["direction"] = {0, -1, 0};  // a point light has no direction
    expectContains(loadError(doc), {"lights[0].direction", "unknown key"});
    doc = baseScene();
    doc["options"] = {{"volume", {{"res", 64}}}};
    expectContains(loadError(doc), {"options.volume.res", "unknown key"});
}

TEST_F(SceneIoTest, BadMeshesAreErrors) {
    json doc = baseScene();
    write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    doc["virtual"][0] = {{"file", "points.obj"}};
    expectContains(loadError(doc), {"virtual[0].file", "'points.obj' contains no triangles"});

    write("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    doc["virtual"][0] = {{"file", "nan.obj"}};
    expectContains(loadError(doc), {"scene.json: virtual[0]", "vertex", "not finite", "nan"});

    doc["virtual"][0] = json::parse(R"({"shape": {"type": "triangles", "positions": [[0, 0, 0], [1e39, 0, 0],
                                        [0, 1, 0]], "indices": [[0, 1, 2]]}})");
    expectContains(loadError(doc), {"virtual[0].shape.positions[1][0]", "finite"});

    // Finite inputs, but the transform overflows a float.
    doc["virtual"][0] = json::parse(R"({"shape": {"type": "triangles", "positions": [[0, 0, 0], [1e38, 0, 0],
        [0, 1, 0]], "indices": [0, 1, 2]}, "transform": {"scale": 1e10}})");
    expectContains(loadError(doc), {"virtual[0]", "vertex 1", "not finite"});

    doc["virtual"][0] = json::parse(R"({"shape": {"type": "triangles", "positions": [[0, 0, 0], [1, 0, 0],
                                        [0, 1, 0]], "indices": [0, 1, 3]}})");
    expectContains(loadError(doc), {"virtual[0].shape.indices[2]", "out of range", "3 positions"});

    doc["virtual"][0]["shape"]["indices"] = {0, 1};
    expectContains(loadError(doc), {"virtual[0].shape.indices", "multiple of 3"});

    doc["virtual"][0]["shape"]["positions"] = json::parse("[[0, 0, 0], [1, 0, 0], [2, 0, 0]]");
    doc["virtual"][0]["shape"]["indices"] = {0, 1, 2, 2, 1, 0};
    expectContains(loadError(doc), {"virtual[0]", "all 2 triangles", "degenerate"});

    doc["virtual"][0]["shape"]["indices"] = json::array();
    expectContains(loadError(doc), {"virtual[0]", "no triangles"});

    doc["virtual"][0] = {{"shape", {{"type", "cone"}}}};
    expectContains(loadError(doc), {"virtual[0].shape.type", "\"cone\"", "sphere"});
}

TEST_F(SceneIoTest, DegenerateTrianglesAreDroppedSilently) {
    json doc = baseScene();
    doc["virtual"][0] = json::parse(R"({"shape": {"type": "triangles", "smooth": true,
        "positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], "indices": [[0, 1, 2], [0, 1, 3]]}})");
    TriangleMesh mesh = load(doc).virtuals[0];
    EXPECT_EQ(mesh.triangleCount(), 1u);
    EXPECT_EQ(mesh.positions.size(), 3u);  // the vertex only the dropped triangle used is gone
    for (glm::vec3 n : mesh.normals) expectNear(n, {0, 0, 1});
}

TEST_F(SceneIoTest, BadMaterialsAreErrors) {
    json doc = baseScene();
    doc["virtual"][0]["material"] = {{"roughness", 0.5}, {"glossiness", 0.5}};
    expectContains(loadError(doc), {"virtual[0].material.glossiness", "not both"});
    doc["virtual"][0]["material"] = {{"roughness", 0}};
    expectContains(loadError(doc), {"virtual[0].material.roughness", "(0, 1]"});
    doc["virtual"][0]["material"] = {{"albedo", {0.5, 1.5, 0.5}}};
    expectContains(loadError(doc), {"virtual[0].material.albedo[1]", "[0, 1]"});
    doc["virtual"][0]["material"] = {{"albedo", {0.5, 0.7, 0.5}}, {"specular", 0.4}};
    expectContains(loadError(doc), {"virtual[0].material", "albedo + specular exceeds 1 in channel g"});

    // Values from the file count too: Kd 0.3 + Ks 0.6 is fine, a JSON albedo of 0.5 with Ks 0.6 is not.
    write("two.obj", kTwoCubesObj);
    write("two.mtl", kTwoCubesMtl);
    doc["virtual"][0] = {{"file", "two.obj"}, {"material", {{"albedo", 0.5}}}};
    expectContains(loadError(doc), {"virtual[0].material", "exceeds 1", "material 'shiny'"});
}

TEST_F(SceneIoTest, BadCamerasAreErrors) {
    json doc = baseScene();
    doc.erase("camera");
    expectContains(loadError(doc), {"scene.json: camera", "missing"});
    doc = baseScene();
    doc["camera"]["width"] = 0;
    expectContains(loadError(doc), {"camera.width", "[1, 16384]"});
    doc = baseScene();
    doc["camera"]["fx"] = 100;
    expectContains(loadError(doc), {"camera.fov_y_deg", "not both"});
    doc = baseScene();
    doc["camera"]["fov_y_deg"] = 180;
    expectContains(loadError(doc), {"camera.fov_y_deg", "(0, 180)"});
    doc = baseScene();
    doc["camera"]["look_at"] = {0, 1, 5};
    expectContains(loadError(doc), {"camera.look_at", "view direction"});
    doc = baseScene();
    doc["camera"]["up"] = {0, -2, -10};
    expectContains(loadError(doc), {"camera.up", "parallel"});
    doc = baseScene();
    doc["camera"].erase("position");
    doc["camera"].erase("look_at");
    doc["camera"]["world_from_camera"] =
        json::parse("[[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]");
    expectContains(loadError(doc), {"camera.world_from_camera", "orthonormal"});
}

TEST_F(SceneIoTest, BackgroundOfTheWrongSizeIsAnError) {
    writeImage(Image(32, 32, 3, 0.5f), dir_ / "bg.exr");
    json doc = baseScene();
    doc["background"] = "bg.exr";
    expectContains(loadError(doc), {"scene.json: background", "64x48", "32x32"});
    doc["background"] = "missing.png";
    expectContains(loadError(doc), {"scene.json: background", "missing.png"});
}

TEST_F(SceneIoTest, BadOptionsAreErrors) {
    struct Case {
        const char* key;
        json value;
        const char* expected;
    };
    const Case cases[] = {
        {"/options/volume/resolution", 0, "expected a power of two in [4, 1024], got 0"},
        {"/options/volume/resolution", -8, "expected a power of two in [4, 1024], got -8"},
        {"/options/volume/resolution", 100, "expected a power of two in [4, 1024], got 100"},
        {"/options/volume/resolution", 2048, "expected a power of two in [4, 1024], got 2048"},
        {"/options/volume/extent_scale", 0, "(0, inf)"},
        {"/options/volume/size", 2, "give both or neither"},
        {"/options/rsm/resolution", 8, "[16, 8192]"},
        {"/options/diffuse/count", 65, "[1, 64]"},
        {"/options/diffuse/aperture_deg", 180, "[0, 180)"},
        {"/options/specular/min_aperture_deg", 120, "at most max_aperture_deg"},
        {"/options/shadow/aperture_deg", 0, "(0, 90]"},
        {"/options/trace/step_scale", 0.01, "[0.05, 4]"},
        {"/options/trace/max_occlusion", 0.2, "[0.5, 1]"},
        {"/options/trace/backface_weight", 1.5, "[0, 1]"},
        {"/options/trace/accumulation", "back_to_front", "\"paper\" or \"front_to_back\""},
        {"/options/render/samples_per_pixel", 8, "1, 4, 9 or 16"},
    };
    for (const Case& c : cases) {
        json doc = baseScene();
        doc[json::json_pointer(c.key)] = c.value;
        std::string path = std::string(c.key).substr(1);
        std::replace(path.begin(), path.end(), '/', '.');
        expectContains(loadError(doc), {"scene.json: " + path + ":", c.expected});
    }
}

TEST(RenderMemoryTest, TooLargeForMemoryNamesTheKeyAndBothSizes) {
    Options options;
    options.volume.resolution = 1024;
    Camera camera;
    constexpr uint64_t kGiB = uint64_t{1} << 30;
    // 112 bytes per voxel at a render's peak: 112 GiB, with the program and a 640x480 frame.
    EXPECT_NEAR(static_cast<double>(estimateRenderMemory(options, camera, 0)) / kGiB, 112.35, 0.1);
    try {
        checkRenderMemory(options, camera, 1, 16 * kGiB, "scene.json");
        ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
        expectContains(e.what(), {"scene.json: options.volume.resolution", "112.", "16.0 GiB"});
    }
    EXPECT_NO_THROW(checkRenderMemory(options, camera, 1, 128 * kGiB, "scene.json"));
    // Large RSMs for many lights dominate: then the RSM resolution is the key to change.
    options.volume.resolution = 64;
    options.rsm.resolution = 8192;
    try {
        checkRenderMemory(options, camera, 4, 16 * kGiB, "scene.json");
        ADD_FAILURE() << "expected an InputError";
    } catch (const InputError& e) {
        expectContains(e.what(), {"scene.json: options.rsm.resolution"});
    }
}

TEST_F(SceneIoTest, BadLightsAreErrors) {
    json doc = baseScene();
    doc["lights"][0]["type"] = "area";
    expectContains(loadError(doc), {"scene.json: lights[0].type", "\"area\"", "\"point\""});
    doc["lights"][0].erase("type");
    expectContains(loadError(doc), {"lights[0].type", "missing"});
    doc["lights"][0] = json::parse(R"({"type": "spot", "position": [0, 1, 0], "direction": [0, -1, 0],
                                       "inner_angle_deg": 50, "outer_angle_deg": 40})");
    expectContains(loadError(doc), {"lights[0].inner_angle_deg", "at most outer_angle_deg"});
    doc["lights"][0] = json::parse(R"({"type": "directional", "direction": [0, 0, 0]})");
    expectContains(loadError(doc), {"lights[0].direction", "non-zero"});
    doc["lights"][0] = json::parse(R"({"type": "point", "position": [0, 1, 0], "intensity": -1})");
    expectContains(loadError(doc), {"lights[0].intensity", "[0, inf)"});
    doc["lights"][0] = json::parse(R"({"type": "point"})");
    expectContains(loadError(doc), {"lights[0].position", "missing"});
}

TEST_F(SceneIoTest, SceneWithoutMeshesIsAnError) {
    json doc = baseScene();
    doc["scene"] = json::array();
    doc.erase("virtual");
    expectContains(loadError(doc), {"scene.json", "at least one", "\"virtual\""});
    doc = baseScene();
    doc["virtual"][0] = json::object();
    expectContains(loadError(doc), {"scene.json: virtual[0]", "\"file\" or a \"shape\""});
}

}  // namespace
}  // namespace deltagi
