// Hostile input to the loaders (issue 11): strict JSON (nesting depth, repeated keys, numbers beyond a
// double), mesh files whose headers claim more than they hold, the memory guard, intensities that would
// overflow the render's floats, and the warnings for scenes that render but not as meant. The bad-input
// corpus (tests/bad-inputs) runs the same cases through the command line.
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>

#include <gtest/gtest.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "scene/json_reader.h"
#include "scene/mesh_io.h"
#include "test_errors.h"

namespace deltagi {
namespace {

using test::expectContains;
using test::inputErrorOf;

namespace fs = std::filesystem;
using nlohmann::json;

std::string nested(size_t depth) {
    return std::string(depth, '[') + std::string(depth, ']');
}

// ---- JSON -------------------------------------------------------------------------------------------------

TEST(ParseJsonTest, ReadsWhatNlohmannReads) {
    const std::string text = R"({"a": [1, 2.5, "x", null, true, {"b": {}}], "c": -3})";
    EXPECT_EQ(parseJson(text, "f.json"), json::parse(text));
}

TEST(ParseJsonTest, RepeatedKeysAreErrorsNamingThePath) {
    expectContains(inputErrorOf([] { parseJson(R"({"a": [1, {"b": 1, "b": 2}]})", "f.json"); }),
                   {"f.json: a[1].b: duplicate key"});
    // The same key in different objects is fine.
    EXPECT_NO_THROW(parseJson(R"({"a": {"b": 1}, "c": {"b": 2}})", "f.json"));
}

TEST(ParseJsonTest, NestingIsBoundedAndTheMessageStaysShort) {
    EXPECT_NO_THROW(parseJson(nested(kMaxJsonDepth), "f.json"));
    const std::string message = inputErrorOf([] { parseJson(nested(kMaxJsonDepth + 1), "f.json"); });
    expectContains(message, {"f.json: ", "nested more than 128 levels deep"});
    // 100,000 levels overflowed the stack when a message printed the value; the path in the message is cut.
    const std::string deep = inputErrorOf([] { parseJson(nested(100000), "f.json"); });
    EXPECT_LT(deep.size(), 200u) << deep;
}

// A syntax error after a long token: the message was taken apart with std::regex, whose matching recursed
// once per character of the token and overflowed the stack (found by `deltagi serve` on a small thread
// stack).
TEST(ParseJsonTest, ASyntaxErrorAfterALongTokenIsOneMessage) {
    const std::string text = "{\"a\": \"" + std::string(2000000, 'x');  // a string that never ends
    const std::string message = inputErrorOf([&] { parseJson(text, "f.json"); });
    expectContains(message, {"f.json: line 1, column ", "syntax error while parsing value"});
    EXPECT_EQ(message.find("[json.exception"), std::string::npos) << message.substr(0, 200);
}

TEST(ParseJsonTest, NumbersBeyondADoubleNameTheLineAndTheKey) {
    expectContains(inputErrorOf([] { parseJson("{\"a\": {\"b\": [0,\n 1, 1e999]}}", "f.json"); }),
                   {"f.json: line 2, column ", "a.b[2]: the number 1e999 is out of range"});
}

TEST(ParseJsonTest, SyntaxErrorsNameTheLineAndColumn) {
    expectContains(inputErrorOf([] { parseJson("{\"a\": 1,\n ,}", "f.json"); }),
                   {"f.json: line 2, column 2: syntax error"});
}

TEST(ParseJsonTest, OverrideValuesThatAreNotStrictJsonAreStrings) {
    json document = {{"description", "x"}};
    applyOverride(document, "description=" + nested(1000));
    EXPECT_EQ(document["description"], nested(1000));
    applyOverride(document, R"(description={"a": 1, "a": 2})");
    EXPECT_TRUE(document["description"].is_string());
    applyOverride(document, "description=[1, 2]");
    EXPECT_EQ(document["description"], json::array({1, 2}));
}

// ---- the memory guard -------------------------------------------------------------------------------------

TEST(RenderMemoryTest, EachLightCountsItsTwoMaps) {
    Options options;
    Camera camera;
    // The scene's map and the update with the objects: 2 x 6 faces x 384^2 texels x 48 bytes = 85 MB.
    const uint64_t perLight =
        estimateRenderMemory(options, camera, 2) - estimateRenderMemory(options, camera, 1);
    EXPECT_EQ(perLight, uint64_t{2} * 6 * 384 * 384 * 48);
}

// options.rsm.resolution "auto" sizes a point light's maps by the volume (96^2 at 32^3) and a directional
// light's at 512^2: the maps of forty lights in a room at 32^3 count 0.21 GB, not 6 GB.
TEST(RenderMemoryTest, AutoResolutionCountsEachLightsOwnMaps) {
    Options options;
    options.volume.resolution = 32;
    Camera camera;
    const uint64_t point =
        estimateRenderMemory(options, camera, 2) - estimateRenderMemory(options, camera, 1);
    EXPECT_EQ(point, uint64_t{2} * 6 * 96 * 96 * 48);
    const uint64_t directional =
        estimateRenderMemory(options, camera, 1, 1) - estimateRenderMemory(options, camera, 1, 0);
    EXPECT_EQ(directional, uint64_t{2} * 6 * 256 * 256 * 48);
    EXPECT_LT(estimateRenderMemory(options, camera, 40) - estimateRenderMemory(options, camera, 0),
              uint64_t{400} << 20);
}

TEST(RenderMemoryTest, ALargeCameraNamesTheCameraAndTheFrameImages) {
    Options options;
    Camera camera;
    camera.width = camera.height = 16384;
    constexpr uint64_t kGiB = uint64_t{1} << 30;
    expectContains(inputErrorOf([&] { checkRenderMemory(options, camera, 1, 16 * kGiB, "s.json"); }),
                   {"s.json: camera: 16384x16384 pixels at 4 samples per pixel", "frame images 140.0 GiB"});
}

// A shape's triangles count as rendered (256 bytes each): 100 million of them name the meshes.
TEST(RenderMemoryTest, ManyTrianglesNameTheMeshes) {
    Options options;
    options.volume.resolution = 16;
    Camera camera;
    constexpr uint64_t kGiB = uint64_t{1} << 30;
    EXPECT_EQ(
        estimateRenderMemory(options, camera, 1, 0, 1000) - estimateRenderMemory(options, camera, 1, 0, 0),
        256'000u);
    expectContains(inputErrorOf([&] {
                       checkRenderMemory(options, camera, 1, 16 * kGiB, "s.json: virtual[0]", 0, 100'000'000);
                   }),
                   {"s.json: virtual[0]: meshes: 100000000 triangles", "meshes 23.8 GiB"});
}

// ---- mesh files -------------------------------------------------------------------------------------------

class MeshFileTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("deltagi_loader_hardening_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path write(const std::string& name, const std::string& bytes) {
        const fs::path path = dir_ / name;
        std::ofstream(path, std::ios::binary) << bytes;
        return path;
    }
    fs::path dir_;
};

constexpr uint64_t kPlenty = uint64_t{1} << 40;

std::string plyHeader(const std::string& format, int vertices, int faces) {
    return "ply\nformat " + format + " 1.0\nelement vertex " + std::to_string(vertices) +
           "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(faces) +
           "\nproperty list uchar int vertex_indices\nend_header\n";
}

TEST_F(MeshFileTest, HeaderCountsBeyondTheFileAreErrors) {
    // Binary: 3 vertices of 12 bytes and 1 face of at least 1 byte need 37 bytes; 36 are there.
    const fs::path shortPly =
        write("short.ply", plyHeader("binary_little_endian", 3, 1) + std::string(36, '\0'));
    expectContains(inputErrorOf([&] { checkMeshFileClaims(shortPly, "where", kPlenty); }),
                   {"where: 'short.ply' is truncated or corrupt", "3 vertex elements, 1 face element",
                    "at least 37 bytes", "36 bytes after the header"});
    const fs::path fullPly =
        write("full.ply", plyHeader("binary_little_endian", 3, 1) + std::string(37, '\0'));
    EXPECT_NO_THROW(checkMeshFileClaims(fullPly, "where", kPlenty));
    // ASCII: at least 2 characters per property.
    const fs::path ascii = write("ascii.ply", plyHeader("ascii", 1000, 0) + "0 0 0\n");
    expectContains(inputErrorOf([&] { checkMeshFileClaims(ascii, "where", kPlenty); }),
                   {"1000 vertex elements"});
    // A malformed header: Assimp's PLY reader crashed or spun on such (fuzz findings); lines without a
    // keyword are skipped, as Assimp skips them.
    const fs::path badType =
        write("type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty flt x\nend_header\n0\n");
    expectContains(inputErrorOf([&] { checkMeshFileClaims(badType, "where", kPlenty); }),
                   {"where: 'type.ply' is corrupt: line 4 of its PLY header is \"property flt x\""});
    const fs::path binary = write("binary.ply", std::string("ply\nformat ascii 1\0\0\nend_header\n", 32));
    expectContains(inputErrorOf([&] { checkMeshFileClaims(binary, "where", kPlenty); }),
                   {"line 2 of its PLY header", "expected printable text"});
    const fs::path noKeyword = write("blender.ply",
                                     "ply\nformat ascii 1.0\nCreated by Blender\nelement vertex 1\n"
                                     "property float x\nend_header\n0\n");
    EXPECT_NO_THROW(checkMeshFileClaims(noKeyword, "where", kPlenty));
    const fs::path noEnd = write("noend.ply", "ply\nformat ascii 1.0\nelement vertex 1\n");
    expectContains(inputErrorOf([&] { checkMeshFileClaims(noEnd, "where", kPlenty); }),
                   {"its PLY header has no line \"end_header\""});
    // A count beyond 64 bits.
    const fs::path hugeCount =
        write("count.ply", "ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n");
    expectContains(inputErrorOf([&] { checkMeshFileClaims(hugeCount, "where", kPlenty); }),
                   {"where: 'count.ply' is corrupt: line 3", "\"element NAME COUNT\" with a whole number"});
    // OFF, counts on the first line or on their own.
    const fs::path off = write("huge.off", "OFF\n353535235358 6 0\n0 0 0\n");
    expectContains(inputErrorOf([&] { checkMeshFileClaims(off, "where", kPlenty); }),
                   {"353535235358 vertex elements"});
    const fs::path offInline = write("inline.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_NO_THROW(checkMeshFileClaims(offInline, "where", kPlenty));
}

TEST_F(MeshFileTest, MeshesLargerThanMemoryAreRefusedBeforeLoading) {
    const fs::path ply = write("ok.ply", plyHeader("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    EXPECT_NO_THROW(checkMeshFileClaims(ply, "where", kPlenty));
    expectContains(inputErrorOf([&] { checkMeshFileClaims(ply, "where", 100); }),
                   {"where: loading 'ok.ply' needs about", "GiB of physical memory"});
    // Formats without counts: in proportion to the file's size.
    const fs::path obj = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    EXPECT_NO_THROW(checkMeshFileClaims(obj, "where", kPlenty));
    expectContains(inputErrorOf([&] { checkMeshFileClaims(obj, "where", 100); }),
                   {"loading 'tri.obj' needs about"});
}

TEST_F(MeshFileTest, BrokenIndicesAndNonFiniteVerticesAreErrorsNotCrashes) {
    const std::string vertices = "0 0 0\n1 0 0\n0 1 0\n";
    for (const char* face : {"3 0 1 7\n", "3 0 -1 2\n"}) {
        const fs::path ply = write("bad.ply", plyHeader("ascii", 3, 1) + vertices + face);
        expectContains(inputErrorOf([&] { loadMeshFile(ply, "where", "bad"); }), {"where: ", "out of range"});
    }
    const fs::path obj = write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
    expectContains(inputErrorOf([&] { loadMeshFile(obj, "where", "nan"); }),
                   {"where: vertex 2 of mesh 'nan' is not finite: (nan, 1, 0)"});
    // A good file still loads, with the names the scene reader gives.
    const fs::path good = write("good.ply", plyHeader("ascii", 3, 1) + vertices + "3 0 1 2\n");
    const std::vector<FileMesh> meshes = loadMeshFile(good, "where", "good");
    ASSERT_EQ(meshes.size(), 1u);
    EXPECT_EQ(meshes[0].mesh.name, "good");
    EXPECT_EQ(meshes[0].mesh.triangles.size(), 1u);
}

// Files whose nesting would overflow the stack of Assimp's recursive readers are refused before it reads them
// (issue 37); so are glTF node cycles and buffers that are not regular files (a FIFO would block the read).
TEST_F(MeshFileTest, DeepNestingAndFifosAreRefusedBeforeAssimp) {
    // 20,000 glTF nodes, each the child of the one before.
    std::string nodes;
    for (int i = 0; i < 20000; ++i)
        nodes += (i ? "," : "") +
                 (i + 1 < 20000 ? "{\"children\":[" + std::to_string(i + 1) + "]}" : std::string("{}"));
    const std::string asset = R"("asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}])";
    const fs::path chain = write("chain.gltf", "{" + asset + ",\"nodes\":[" + nodes + "]}");
    expectContains(inputErrorOf([&] { loadMeshFile(chain, "where", "chain"); }),
                   {"where: 'chain.gltf': its nodes nest 20000 levels deep, more than the 1000"});
    const fs::path brackets = write("brackets.gltf", "{\"a\":" + std::string(200000, '[') + "}");
    expectContains(inputErrorOf([&] { loadMeshFile(brackets, "where", "b"); }),
                   {"'brackets.gltf' nests 200001 levels deep"});
    const fs::path cycle =
        write("cycle.gltf", "{" + asset + R"(,"nodes":[{"children":[1]},{"children":[0]}]})");
    expectContains(inputErrorOf([&] { loadMeshFile(cycle, "where", "c"); }), {"a cycle"});
    std::string collada = "<?xml version=\"1.0\"?><COLLADA><library_visual_scenes><visual_scene>";
    for (int i = 0; i < 20000; ++i) collada += "<node>";
    for (int i = 0; i < 20000; ++i) collada += "</node>";
    collada += "</visual_scene></library_visual_scenes></COLLADA>";
    const fs::path dae = write("deep.dae", collada);
    expectContains(inputErrorOf([&] { loadMeshFile(dae, "where", "d"); }), {"'deep.dae' nests 20003 levels"});
    // A buffer that is a FIFO.
    const fs::path fifo = dir_ / "buffer.bin";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    const fs::path piped = write(
        "piped.gltf", "{" + asset + R"(,"nodes":[{}],"buffers":[{"uri":"buffer.bin","byteLength":36}]})");
    expectContains(inputErrorOf([&] { loadMeshFile(piped, "where", "p"); }),
                   {"'piped.gltf': buffer 'buffer.bin' is not a regular file"});
    // A scene file that is a FIFO.
    const fs::path scene = dir_ / "scene.json";
    ASSERT_EQ(mkfifo(scene.c_str(), 0600), 0);
    expectContains(inputErrorOf([&] { loadScene(scene); }),
                   {"scene.json: cannot open scene file: not a regular file"});
}

// ---- scenes -----------------------------------------------------------------------------------------------

json smallScene() {
    return json::parse(R"({
        "camera": {"width": 64, "height": 48, "fov_y_deg": 60, "position": [0, 1, 5], "look_at": [0, 0, 0]},
        "scene": [{"name": "floor", "shape": {"type": "quad", "size": [10, 10]}}],
        "virtual": [{"name": "box", "shape": {"type": "box", "size": [1, 1, 1]},
                     "transform": {"translate": [0, 0.5, 0]}}],
        "lights": [{"type": "point", "position": [0, 5, 0], "intensity": 10}]
    })");
}

Scene loadFromJson(const json& document) {
    return loadScene(document, "s.json");
}

TEST(SceneOverflowTest, IntensitiesThatWouldOverflowAreRefused) {
    json scene = smallScene();
    scene["lights"][0]["intensity"] = 1e20;
    EXPECT_NO_THROW(loadFromJson(scene));
    scene["lights"][0]["intensity"] = 6e19;
    scene["lights"][0]["color"] = {2, 1, 1};  // the product counts
    expectContains(inputErrorOf([&] { loadFromJson(scene); }),
                   {"s.json: lights[0].intensity: intensity times color is 1.2e+20, more than 1e+20"});
    scene = smallScene();
    scene["virtual"][0]["material"] = {{"emission", 1e10}, {"emission_scale", 1e11}};
    expectContains(inputErrorOf([&] { loadFromJson(scene); }),
                   {"s.json: virtual[0].material.emission_scale: mesh 'box': emission times emission_scale"});
}

TEST(SceneWarningTest, AGoodSceneHasNone) {
    EXPECT_TRUE(loadFromJson(smallScene()).warnings.empty());
}

// Mesh files that cannot be read say why in one line: a symbolic link loop, a device, a PLY whose face
// claims 4e9 indices (Assimp's allocation fails inside it).
TEST_F(MeshFileTest, UnreadableFilesSayWhy) {
    fs::create_symlink(dir_ / "loop-b.ply", dir_ / "loop-a.ply");
    fs::create_symlink(dir_ / "loop-a.ply", dir_ / "loop-b.ply");
    const std::string header =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uint uint vertex_indices\nend_header\n";
    std::string data(9 * 4, '\0');
    const uint32_t claimed = 4000000000u;
    data.append(reinterpret_cast<const char*>(&claimed), 4);
    data.append(12, '\0');
    write("claims.ply", header + data);
    for (const auto& [file, message] : std::vector<std::pair<std::string, std::string>>{
             {(dir_ / "loop-a.ply").string(), "Too many levels of symbolic links"},
             {"/dev/zero", "'/dev/zero' is not a regular file"},
             {(dir_ / "claims.ply").string(), "face 0 of its data claims a list of 4000000000 items"}}) {
        json scene = smallScene();
        scene["scene"][0] = {{"file", file}};
        expectContains(inputErrorOf([&] { loadFromJson(scene); }), {"s.json: scene[0].file: ", message});
    }
}

TEST(SceneWarningTest, NoLight) {
    json scene = smallScene();
    scene["lights"][0]["intensity"] = 0;
    const Scene loaded = loadFromJson(scene);
    ASSERT_EQ(loaded.warnings.size(), 1u);
    expectContains(loaded.warnings[0], {"s.json: lights: the scene has no light"});
    // An emitting surface is a light.
    scene["scene"][0]["material"] = {{"emission", 1}};
    EXPECT_TRUE(loadFromJson(scene).warnings.empty());
}

TEST(SceneWarningTest, AVirtualMeshAroundTheCamera) {
    json scene = smallScene();
    scene["virtual"][0]["shape"]["size"] = {20, 20, 20};
    const Scene loaded = loadFromJson(scene);
    ASSERT_FALSE(loaded.warnings.empty());
    expectContains(loaded.warnings[0], {"s.json: virtual: mesh 'box' encloses the camera"});
    // The camera inside the bounds of an open mesh (a bowl seen from above) is not inside it.
    scene["virtual"][0] = {{"name", "quad"},
                           {"shape", {{"type", "quad"}, {"size", {20, 20}}}},
                           {"transform", {{"rotate_deg", {10, 0, 0}}}}};
    for (const std::string& warning : loadFromJson(scene).warnings)
        EXPECT_EQ(warning.find("encloses"), std::string::npos) << warning;
}

TEST(SceneWarningTest, AVirtualMeshOutsideTheVolume) {
    json scene = smallScene();
    scene["options"] = {{"volume", {{"center", {0, 0, 0}}, {"size", 4}}}};
    EXPECT_TRUE(loadFromJson(scene).warnings.empty());
    scene["virtual"][0]["transform"]["translate"] = {30, 0.5, 0};
    Scene loaded = loadFromJson(scene);
    ASSERT_EQ(loaded.warnings.size(), 1u);
    expectContains(loaded.warnings[0], {"s.json: virtual: mesh 'box' lies outside the voxel volume"});
    scene["virtual"][0]["transform"]["translate"] = {2, 0.5, 0};
    loaded = loadFromJson(scene);
    ASSERT_EQ(loaded.warnings.size(), 1u);
    expectContains(loaded.warnings[0], {"mesh 'box' extends beyond the voxel volume"});
}

}  // namespace
}  // namespace deltagi
