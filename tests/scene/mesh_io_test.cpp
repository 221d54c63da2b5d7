// Mesh files through Assimp (mesh_io.cpp) and the clean-up of meshes (mesh.cpp): per-vertex attributes
// (texture coordinates, tangents, vertex colours) as read, as cleaned and as transformed.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/error.h"
#include "deltagi/image.h"
#include "deltagi/scene_io.h"
#include "deltagi/transforms.h"
#include "io/image_encode.h"
#include "scene/mesh_io.h"
#include "test_errors.h"
#include "test_gltf.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using test::expectContains;
using test::inputErrorOf;

constexpr float kTolerance = 1e-5f;

class MeshIoTest : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ =
            fs::temp_directory_path() / ("deltagi_mesh_io_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path write(const std::string& name, const std::string& text) {
        const fs::path path = dir_ / name;
        std::ofstream(path, std::ios::binary) << text;
        return path;
    }
    fs::path dir_;
};

// The loaded vertex at `position` (meshes may be re-indexed by the loader).
size_t vertexAt(const TriangleMesh& mesh, glm::vec3 position) {
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        if (glm::length(mesh.positions[i] - position) < kTolerance) return i;
    ADD_FAILURE() << "no vertex at (" << position.x << ", " << position.y << ", " << position.z << ")";
    return 0;
}

TEST_F(MeshIoTest, GltfTextureCoordinatesKeepGltfsOrientation) {
    const fs::path file = test::writeQuadGltf(dir_, "quad");
    const std::vector<FileMesh> meshes = loadMeshFile(file, "where", "quad");
    ASSERT_EQ(meshes.size(), 1u);
    const TriangleMesh& mesh = meshes[0].mesh;
    ASSERT_EQ(mesh.uvs.size(), mesh.positions.size());
    ASSERT_EQ(mesh.uvs1.size(), mesh.positions.size());
    for (int corner = 0; corner < 4; ++corner) {
        const size_t i = vertexAt(mesh, test::kQuadPositions[corner]);
        // As written in the file: Assimp's flip of v is undone.
        EXPECT_NEAR(mesh.uvs[i].x, test::kQuadUvs[corner].x, kTolerance);
        EXPECT_NEAR(mesh.uvs[i].y, test::kQuadUvs[corner].y, kTolerance);
        EXPECT_NEAR(mesh.uvs1[i].x, test::kQuadUvs1[corner].x, kTolerance);
        EXPECT_NEAR(mesh.uvs1[i].y, test::kQuadUvs1[corner].y, kTolerance);
        // glTF's COLOR_0 is linear: as written.
        ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
        EXPECT_NEAR(glm::length(mesh.colors[i] - test::kQuadColour), 0.0f, kTolerance);
    }
}

TEST_F(MeshIoTest, TangentsFollowUAndTheBitangentPointsUpTheImage) {
    const std::vector<FileMesh> meshes = loadMeshFile(test::writeQuadGltf(dir_, "quad"), "where", "quad");
    TriangleMesh mesh = meshes[0].mesh;
    cleanMesh(mesh, "where");
    ASSERT_EQ(mesh.tangents.size(), mesh.positions.size());
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec4 t = mesh.tangents[i];
        // u grows along +x; the image's top is at +y (v = 0 there): bitangent = w cross(n, t) = +y.
        EXPECT_NEAR(glm::length(glm::vec3(t) - glm::vec3(1, 0, 0)), 0.0f, 1e-4f);
        EXPECT_EQ(t.w, 1.0f);
        const glm::vec3 bitangent = t.w * glm::cross(mesh.normals[i], glm::vec3(t));
        EXPECT_NEAR(glm::length(bitangent - glm::vec3(0, 1, 0)), 0.0f, 1e-4f);
    }
    // A mirror (x -> -x) flips the handedness: the bitangent still points up the image.
    TriangleMesh mirrored = mesh;
    transformMesh(mirrored, glm::scale(glm::mat4(1.0f), glm::vec3(-1, 1, 1)));
    cleanMesh(mirrored, "where");
    for (size_t i = 0; i < mirrored.positions.size(); ++i) {
        const glm::vec4 t = mirrored.tangents[i];
        EXPECT_NEAR(glm::length(glm::vec3(t) - glm::vec3(-1, 0, 0)), 0.0f, 1e-4f);
        EXPECT_EQ(t.w, -1.0f);
        const glm::vec3 bitangent = t.w * glm::cross(mirrored.normals[i], glm::vec3(t));
        EXPECT_NEAR(glm::length(bitangent - glm::vec3(0, 1, 0)), 0.0f, 1e-4f);
    }
}

TEST_F(MeshIoTest, ObjTextureCoordinatesAreFlippedToGltfs) {
    // OBJ's vt has v up from the image's bottom: vt 0 0 is the bottom-left corner, glTF's (0, 1).
    const fs::path obj = write("quad.obj",
                               "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                               "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                               "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
    const TriangleMesh mesh = loadMeshFile(obj, "where", "quad")[0].mesh;
    ASSERT_EQ(mesh.uvs.size(), mesh.positions.size());
    EXPECT_TRUE(mesh.uvs1.empty());
    for (int corner = 0; corner < 4; ++corner) {
        const size_t i = vertexAt(mesh, test::kQuadPositions[corner]);
        EXPECT_NEAR(mesh.uvs[i].x, test::kQuadUvs[corner].x, kTolerance);
        EXPECT_NEAR(mesh.uvs[i].y, test::kQuadUvs[corner].y, kTolerance);
    }
}

TEST_F(MeshIoTest, PlyVertexColoursAreSrgbDecoded) {
    const fs::path ply =
        write("coloured.ply",
              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
              "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
              "0 0 0 255 128 0\n1 0 0 255 128 0\n0 1 0 0 0 255\n3 0 1 2\n");
    const TriangleMesh mesh = loadMeshFile(ply, "where", "coloured")[0].mesh;
    ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
    EXPECT_TRUE(mesh.uvs.empty());
    EXPECT_TRUE(mesh.tangents.empty());  // no texture coordinates, no tangents
    const size_t first = vertexAt(mesh, {0, 0, 0}), third = vertexAt(mesh, {0, 1, 0});
    EXPECT_NEAR(mesh.colors[first].x, 1.0f, kTolerance);
    EXPECT_NEAR(mesh.colors[first].y, srgbToLinearValue(128.0f / 255.0f), 1e-4f);  // 0.2158
    EXPECT_NEAR(mesh.colors[first].y, 0.2158f, 1e-3f);
    EXPECT_NEAR(mesh.colors[first].z, 0.0f, kTolerance);
    EXPECT_NEAR(glm::length(mesh.colors[third] - glm::vec3(0, 0, 1)), 0.0f, kTolerance);
}

TEST_F(MeshIoTest, NonFiniteTextureCoordinatesAreErrorsNamingTheVertex) {
    // Assimp's OBJ reader reads "vt nan 1" as (0, 1); a glTF file's binary buffer holds what it holds.
    const fs::path gltf = test::writeQuadGltf(dir_, "nan-uv");
    {
        std::fstream bin(dir_ / "nan-uv.bin", std::ios::binary | std::ios::in | std::ios::out);
        const float nan = std::nanf("");
        bin.seekp(sizeof(test::kQuadPositions) + 2 * sizeof(glm::vec2));  // u of vertex 2
        bin.write(reinterpret_cast<const char*>(&nan), sizeof(nan));
    }
    expectContains(inputErrorOf([&] { loadMeshFile(gltf, "where", "nan"); }),
                   {"where: texture coordinate (set 0) of vertex 2 of mesh 'nan' is not finite: (nan, 0)",
                    "nan-uv.gltf"});
    // Out of [0, 1] is fine: textures repeat.
    const fs::path wide =
        write("wide-uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt -3 0\nvt 7.5 0\nvt 0 12\nf 1/1 2/2 3/3\n");
    TriangleMesh mesh = loadMeshFile(wide, "where", "wide")[0].mesh;
    EXPECT_NO_THROW(cleanMesh(mesh, "where"));
    EXPECT_NEAR(mesh.uvs[vertexAt(mesh, {1, 0, 0})].x, 7.5f, kTolerance);
}

// A mesh with attributes, a degenerate triangle and a vertex no triangle uses.
TriangleMesh attributedMesh() {
    TriangleMesh mesh;
    mesh.name = "m";
    mesh.positions = {{9, 9, 9}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}};
    mesh.triangles = {{1, 2, 3}, {1, 2, 4}};  // the second is degenerate (collinear)
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const float f = static_cast<float>(i);
        mesh.uvs.emplace_back(f, 0.0f);
        mesh.uvs1.emplace_back(0.0f, f);
        mesh.tangents.emplace_back(1.0f, 0.0f, 0.0f, i == 3 ? -1.0f : 1.0f);
        mesh.colors.emplace_back(f / 10.0f);
    }
    return mesh;
}

TEST(CleanMeshTest, KeepsAttributesWithTheirVertices) {
    TriangleMesh mesh = attributedMesh();
    EXPECT_EQ(cleanMesh(mesh, "where"), 1u);
    ASSERT_EQ(mesh.positions.size(), 3u);  // vertices 0 and 4 go
    ASSERT_EQ(mesh.uvs.size(), 3u);
    ASSERT_EQ(mesh.uvs1.size(), 3u);
    ASSERT_EQ(mesh.tangents.size(), 3u);
    ASSERT_EQ(mesh.colors.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        const float original = static_cast<float>(i + 1);
        EXPECT_EQ(mesh.uvs[i], glm::vec2(original, 0.0f));
        EXPECT_EQ(mesh.uvs1[i], glm::vec2(0.0f, original));
        EXPECT_EQ(mesh.colors[i], glm::vec3(original / 10.0f));
        EXPECT_EQ(mesh.tangents[i].w, i == 2 ? -1.0f : 1.0f);
    }
}

TEST(CleanMeshTest, RefusesBrokenAttributes) {
    TriangleMesh mesh = attributedMesh();
    mesh.uvs[2].y = std::nanf("");
    expectContains(inputErrorOf([&] { cleanMesh(mesh, "where"); }),
                   {"where: texture coordinate (set 0) of vertex 2 of mesh 'm' is not finite"});
    mesh = attributedMesh();
    mesh.uvs1[3].x = INFINITY;
    expectContains(inputErrorOf([&] { cleanMesh(mesh, "where"); }), {"(set 1) of vertex 3"});
    mesh = attributedMesh();
    mesh.colors[1] = glm::vec3(1.5f, 0.0f, 0.0f);
    expectContains(inputErrorOf([&] { cleanMesh(mesh, "where"); }), {"vertex colour of vertex 1", "[0, 1]"});
    mesh = attributedMesh();
    mesh.uvs.pop_back();
    expectContains(inputErrorOf([&] { cleanMesh(mesh, "where"); }),
                   {"mesh 'm' has 4 texture coordinates (set 0) for 5 vertices"});
}

TEST(CleanMeshTest, RepairsTangents) {
    TriangleMesh mesh = attributedMesh();
    mesh.tangents[1] = glm::vec4(std::nanf(""), 0.0f, 0.0f, 1.0f);  // Assimp's mark for degenerate uvs
    mesh.tangents[2] = glm::vec4(2.0f, 0.0f, 3.0f, 1.0f);           // not perpendicular to n = +z
    cleanMesh(mesh, "where");
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec3 t(mesh.tangents[i]);
        EXPECT_NEAR(glm::length(t), 1.0f, 1e-5f);
        EXPECT_NEAR(glm::dot(t, mesh.normals[i]), 0.0f, 1e-5f);
    }
    EXPECT_NEAR(glm::length(glm::vec3(mesh.tangents[1]) - glm::vec3(1, 0, 0)), 0.0f, 1e-5f);
}

TEST(TransformMeshTest, TangentsTurnWithTheMeshAndPlacedCopiesKeepAttributes) {
    TriangleMesh mesh = attributedMesh();
    cleanMesh(mesh, "where");
    const glm::mat4 turn = glm::rotate(glm::mat4(1.0f), glm::radians(90.0f), glm::vec3(0, 0, 1));
    TriangleMesh placed = mesh;
    setTransform(placed, turn);
    ASSERT_EQ(placed.tangents.size(), mesh.tangents.size());
    EXPECT_EQ(placed.uvs, mesh.uvs);
    EXPECT_EQ(placed.uvs1, mesh.uvs1);
    EXPECT_EQ(placed.colors, mesh.colors);
    for (size_t i = 0; i < placed.tangents.size(); ++i) {
        EXPECT_NEAR(glm::length(glm::vec3(placed.tangents[i]) - glm::vec3(0, 1, 0)), 0.0f, 1e-5f);
        EXPECT_EQ(placed.tangents[i].w, mesh.tangents[i].w);
    }
}

// ---- materials
// ----------------------------------------------------------------------------------------------

constexpr glm::vec3 kRed{1, 0, 0}, kBlue{0, 0, 1};

// A 3x2 PNG (not a power of two): red at the top-left texel, blue elsewhere.
void writeMarkedPng(const fs::path& path) {
    Image image(3, 2, 3);
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 3; ++x)
            for (int c = 0; c < 3; ++c) image.at(x, y, c) = (x == 0 && y == 0 ? kRed : kBlue)[c];
    writeImage(image, path);
}

json texturedMaterial() {
    return json::parse(R"({
        "materials": [{"name": "painted",
            "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.6, 0.7, 0.8], "metallicFactor": 0.3,
                "roughnessFactor": 0.4, "baseColorTexture": {"index": 0},
                "metallicRoughnessTexture": {"index": 1, "texCoord": 1}},
            "normalTexture": {"index": 1, "scale": 0.5},
            "occlusionTexture": {"index": 1, "strength": 0.25},
            "emissiveFactor": [1, 0.5, 0], "emissiveTexture": {"index": 0},
            "alphaMode": "MASK", "alphaCutoff": 0.3}],
        "textures": [{"source": 0, "sampler": 0}, {"source": 0, "sampler": 1}],
        "images": [{"uri": "marked.png"}],
        "samplers": [{"wrapS": 33071, "wrapT": 33648, "magFilter": 9728, "minFilter": 9729}, {}]
    })");
}

// The uv at the point (x, y) of the quad: texture coordinates are affine over it.
glm::vec2 uvAt(const TriangleMesh& mesh, glm::vec2 p) {
    const glm::vec2 topLeft = mesh.uvs[vertexAt(mesh, {0, 1, 0})];
    const glm::vec2 topRight = mesh.uvs[vertexAt(mesh, {1, 1, 0})];
    const glm::vec2 bottomLeft = mesh.uvs[vertexAt(mesh, {0, 0, 0})];
    return topLeft + p.x * (topRight - topLeft) + (1.0f - p.y) * (bottomLeft - topLeft);
}

TEST_F(MeshIoTest, GltfMetallicRoughnessMaterialWithTextures) {
    writeMarkedPng(dir_ / "marked.png");
    std::vector<std::string> warnings;
    const std::vector<FileMesh> meshes =
        loadMeshFile(test::writeQuadGltf(dir_, "quad", texturedMaterial()), "where", "quad", &warnings);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    const FileMaterial& m = meshes[0].material;
    EXPECT_EQ(m.name, "painted");
    EXPECT_EQ(m.model, MaterialModel::MetallicRoughness);
    ASSERT_TRUE(m.albedo && m.metallic && m.roughness);
    EXPECT_NEAR(glm::length(*m.albedo - glm::vec3(0.5f, 0.6f, 0.7f)), 0.0f, kTolerance);
    EXPECT_NEAR(m.opacity, 0.8f, kTolerance);
    EXPECT_NEAR(*m.metallic, 0.3f, kTolerance);
    EXPECT_NEAR(*m.roughness, 0.4f, kTolerance);  // perceptual, as in the file
    ASSERT_TRUE(m.emission);
    EXPECT_NEAR(glm::length(*m.emission - glm::vec3(1.0f, 0.5f, 0.0f)), 0.0f, kTolerance);
    EXPECT_EQ(m.alphaMode, AlphaMode::Mask);
    EXPECT_NEAR(m.alphaCutoff, 0.3f, kTolerance);
    ASSERT_TRUE(m.baseColorTexture && m.metallicRoughnessTexture && m.normalTexture && m.occlusionTexture &&
                m.emissiveTexture);
    EXPECT_FALSE(m.specularTexture);
    EXPECT_EQ(m.baseColorTexture.texture->width(), 3);
    EXPECT_EQ(m.baseColorTexture.texture->height(), 2);
    // The sampler and texture coordinate set of each use.
    const TextureSampler& sampler = m.baseColorTexture.sampler;
    EXPECT_EQ(sampler.wrapS, TextureWrap::ClampToEdge);
    EXPECT_EQ(sampler.wrapT, TextureWrap::MirroredRepeat);
    EXPECT_EQ(sampler.magFilter, TextureFilter::Nearest);
    EXPECT_EQ(sampler.minFilter, TextureFilter::Linear);
    EXPECT_FALSE(sampler.mipmaps);
    EXPECT_EQ(m.baseColorTexture.texCoord, 0);
    EXPECT_EQ(m.metallicRoughnessTexture.texCoord, 1);
    EXPECT_EQ(m.metallicRoughnessTexture.sampler.wrapS, TextureWrap::Repeat);
    EXPECT_TRUE(m.metallicRoughnessTexture.sampler.mipmaps);
    EXPECT_NEAR(m.normalScale, 0.5f, kTolerance);
    EXPECT_NEAR(m.occlusionStrength, 0.25f, kTolerance);
    // One image, read once per encoding: sRGB for colour, linear for data.
    EXPECT_EQ(m.baseColorTexture.texture, m.emissiveTexture.texture);
    EXPECT_EQ(m.normalTexture.texture, m.occlusionTexture.texture);
    EXPECT_NE(m.baseColorTexture.texture, m.normalTexture.texture);

    // Orientation: the image's top-left texel is where the quad's top-left corner is.
    const TriangleMesh& mesh = meshes[0].mesh;
    const glm::vec4 nearTopLeft = m.baseColorTexture.sample(uvAt(mesh, {0.05f, 0.95f}), 0.0f);
    const glm::vec4 nearBottomRight = m.baseColorTexture.sample(uvAt(mesh, {0.95f, 0.05f}), 0.0f);
    const glm::vec4 nearTopRight = m.baseColorTexture.sample(uvAt(mesh, {0.95f, 0.95f}), 0.0f);
    EXPECT_NEAR(glm::length(glm::vec3(nearTopLeft) - kRed), 0.0f, 1e-3f);
    EXPECT_NEAR(glm::length(glm::vec3(nearBottomRight) - kBlue), 0.0f, 1e-3f);
    EXPECT_NEAR(glm::length(glm::vec3(nearTopRight) - kBlue), 0.0f, 1e-3f);
}

TEST_F(MeshIoTest, GltfFactorsOutOfRangeAreClampedWithAWarningAndBlendIsMask) {
    json document = json::parse(R"({"materials": [{"name": "odd", "alphaMode": "BLEND",
        "pbrMetallicRoughness": {"metallicFactor": 1.5, "roughnessFactor": -0.5}}]})");
    std::vector<std::string> warnings;
    const std::vector<FileMesh> meshes =
        loadMeshFile(test::writeQuadGltf(dir_, "odd", document), "where", "odd", &warnings);
    const FileMaterial& m = meshes[0].material;
    EXPECT_EQ(*m.metallic, 1.0f);
    EXPECT_GT(*m.roughness, 0.0f);
    EXPECT_LT(*m.roughness, 0.01f);
    EXPECT_EQ(m.alphaMode, AlphaMode::Mask);
    EXPECT_EQ(m.alphaCutoff, 0.5f);
    std::string all;
    for (const std::string& w : warnings) all += w + "\n";
    expectContains(all,
                   {"where: material 'odd' of 'odd.gltf': metallicFactor is 1.5, outside [0, 1]: clamped",
                    "roughnessFactor is -0.5", "alphaMode BLEND is read as MASK"});
}

TEST_F(MeshIoTest, BrokenTexturesAreErrorsNamingFileMaterialAndTexture) {
    json document = texturedMaterial();
    const fs::path gltf = test::writeQuadGltf(dir_, "quad", document);
    // Missing.
    expectContains(
        inputErrorOf([&] { loadMeshFile(gltf, "where", "quad"); }),
        {"where: material 'painted' of 'quad.gltf', ", " texture: texture '", "marked.png", "no such file"});
    // Empty, and not an image.
    write("marked.png", "");
    expectContains(inputErrorOf([&] { loadMeshFile(gltf, "where", "quad"); }),
                   {"material 'painted' of 'quad.gltf', ", "marked.png", "empty"});
    write("marked.png", "this is not a PNG file, just text");
    expectContains(inputErrorOf([&] { loadMeshFile(gltf, "where", "quad"); }),
                   {"material 'painted' of 'quad.gltf', ", "marked.png", "Not a PNG"});
}

TEST_F(MeshIoTest, ObjMaps) {
    writeMarkedPng(dir_ / "kd.png");
    Image flat(4, 4, 3);  // a normal map's flat colour (0.5, 0.5, 1), linear
    Image height(4, 4, 3, 0.2f);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
            flat.at(x, y, 0) = flat.at(x, y, 1) = srgbToLinearValue(0.5f), flat.at(x, y, 2) = 1;
    writeImage(flat, dir_ / "normals.png");
    writeImage(height, dir_ / "height.png");
    write("m.mtl",
          "newmtl a\nKd 0.5 0.5 0.5\nKs 0.1 0.1 0.1\nNs 10\nmap_Kd kd.png\nmap_Ks kd.png\n"
          "map_Bump normals.png\nmap_Ns height.png\nmap_Pr height.png\nmap_d kd.png\n"
          "newmtl b\nKd 0.5 0.5 0.5\nbump height.png\n");
    const fs::path obj =
        write("m.obj",
              "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
              "usemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 1/1 3/3 4/4\n");
    std::vector<std::string> warnings;
    const std::vector<FileMesh> meshes = loadMeshFile(obj, "where", "m", &warnings);
    ASSERT_EQ(meshes.size(), 2u);
    const FileMaterial& a = meshes[0].material.name == "a" ? meshes[0].material : meshes[1].material;
    const FileMaterial& b = meshes[0].material.name == "a" ? meshes[1].material : meshes[0].material;
    EXPECT_EQ(a.model, MaterialModel::Phong);
    ASSERT_TRUE(a.baseColorTexture && a.specularTexture && a.normalTexture && a.shininessTexture &&
                a.roughnessTexture);
    EXPECT_EQ(a.shininessTexture.texture, a.roughnessTexture.texture);  // both linear scalar maps
    EXPECT_EQ(a.baseColorTexture.texture, a.specularTexture.texture);   // one file, one encoding: read once
    EXPECT_FALSE(b.normalTexture);                                      // a height map
    std::string all;
    for (const std::string& w : warnings) all += w + "\n";
    expectContains(all, {"where: material 'a' of 'm.obj': an opacity map (map_d) ('kd.png') is ignored",
                         "material 'b' of 'm.obj': the bump map", "is a height map"});
    // OBJ's vt orientation reaches the texture as glTF's: the image's top-left texel at the top-left corner.
    const TriangleMesh& mesh = meshes[0].material.name == "a" ? meshes[0].mesh : meshes[1].mesh;
    const size_t right = vertexAt(mesh, {1, 1, 0});
    TextureSampler nearest;
    nearest.magFilter = TextureFilter::Nearest;
    const glm::vec2 nearTopLeft = mesh.uvs[right] + glm::vec2(-0.9f, 0.1f);
    EXPECT_NEAR(glm::length(glm::vec3(a.baseColorTexture.texture->sample(nearTopLeft, 0.0f, nearest)) - kRed),
                0.0f, 1e-3f);
}

TEST_F(MeshIoTest, SampleModelBoxTexturedLoads) {
    const fs::path glb = "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb";
    if (!fs::exists(glb)) GTEST_SKIP() << glb << " is missing: install Debian's assimp-testmodels";
    std::vector<std::string> warnings;
    const std::vector<FileMesh> meshes = loadMeshFile(glb, "where", "box", &warnings);
    ASSERT_EQ(meshes.size(), 1u);
    const FileMaterial& m = meshes[0].material;
    EXPECT_EQ(m.model, MaterialModel::MetallicRoughness);
    ASSERT_TRUE(m.baseColorTexture);  // embedded PNG ("*0"), decoded from memory
    EXPECT_GT(m.baseColorTexture.texture->width(), 1);
    EXPECT_EQ(meshes[0].mesh.uvs.size(), meshes[0].mesh.positions.size());
    EXPECT_EQ(meshes[0].mesh.tangents.size(), meshes[0].mesh.positions.size());
    EXPECT_TRUE(warnings.empty());
    // The .gltf with its PNG beside it gives the same image.
    const fs::path gltf = "/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf";
    if (fs::exists(gltf)) {
        const FileMaterial external = loadMeshFile(gltf, "where", "box")[0].material;
        ASSERT_TRUE(external.baseColorTexture);
        EXPECT_EQ(external.baseColorTexture.texture->width(), m.baseColorTexture.texture->width());
        EXPECT_EQ(external.baseColorTexture.texture->average(), m.baseColorTexture.texture->average());
    }
}

// ---- scene files
// ----------------------------------------------------------------------------------------------

json sceneWith(json material, json shape = {{"type", "quad"}, {"size", {1, 1}}}) {
    json scene = json::parse(R"({
        "camera": {"width": 32, "height": 24, "fov_y_deg": 60, "position": [0, 1, 5], "look_at": [0, 0, 0]},
        "lights": [{"type": "point", "position": [0, 5, 0], "intensity": 10}]})");
    json entry = {{"name", "thing"}, {"material", material}};
    if (shape.is_string())
        entry["file"] = shape;
    else
        entry["shape"] = shape;
    scene["virtual"] = {entry};
    return scene;
}

TEST_F(MeshIoTest, SceneMetallicRoughnessMaterials) {
    const fs::path sceneFile = dir_ / "s.json";
    Scene scene = loadScene(sceneWith({{"base_color", {0.9, 0.5, 0.1, 0.5}}, {"roughness", 0.3}}), sceneFile);
    const Material& m = scene.virtuals[0].material;
    EXPECT_EQ(m.model, MaterialModel::MetallicRoughness);
    EXPECT_NEAR(m.albedo.y, 0.5f, kTolerance);
    EXPECT_NEAR(m.opacity, 0.5f, kTolerance);
    EXPECT_EQ(m.metallic, 0.0f);
    EXPECT_NEAR(m.roughness, 0.3f, kTolerance);
    EXPECT_EQ(loadScene(sceneWith({{"metallic", 1}}), sceneFile).virtuals[0].material.model,
              MaterialModel::MetallicRoughness);
    EXPECT_EQ(loadScene(sceneWith({{"albedo", 0.5}}), sceneFile).virtuals[0].material.model,
              MaterialModel::Phong);

    expectContains(inputErrorOf([&] {
                       loadScene(sceneWith({{"specular", 0.1}, {"metallic", 0.5}}), sceneFile);
                   }),
                   {"s.json: virtual[0].material.metallic: give either \"specular\""});
    expectContains(inputErrorOf([&] {
                       loadScene(sceneWith({{"metallic", 1.5}}), sceneFile);
                   }),
                   {"s.json: virtual[0].material.metallic: expected a number in [0, 1], got 1.5"});
    expectContains(inputErrorOf([&] {
                       loadScene(sceneWith({{"roughness", -1}}), sceneFile);
                   }),
                   {"s.json: virtual[0].material.roughness: expected a number in (0, 1]"});
    expectContains(inputErrorOf([&] {
                       loadScene(sceneWith({{"alpha_mode", "MASK"}}), sceneFile);
                   }),
                   {"virtual[0].material.alpha_mode: expected \"opaque\", \"mask\" or \"blend\""});
    expectContains(inputErrorOf([&] {
                       loadScene(sceneWith({{"base_color_texture", "none.png"}}), sceneFile);
                   }),
                   {"s.json: virtual[0].material.base_color_texture: file not found", "none.png"});
    write("garbage.png", "not an image");
    expectContains(inputErrorOf([&] {
                       loadScene(sceneWith({{"normal_texture", "garbage.png"}}), sceneFile);
                   }),
                   {"s.json: virtual[0].material.normal_texture: texture '", "garbage.png"});
}

TEST_F(MeshIoTest, SceneTexturesOverrideTheFilesAndNeedTextureCoordinates) {
    writeMarkedPng(dir_ / "marked.png");
    test::writeQuadGltf(dir_, "quad", texturedMaterial());
    const fs::path sceneFile = dir_ / "s.json";
    // The file's material, with the JSON's keys over it.
    Scene scene =
        loadScene(sceneWith({{"metallic", 0.9}, {"alpha_mode", "blend"}, {"occlusion_texture", "marked.png"}},
                            "quad.gltf"),
                  sceneFile);
    const Material& m = scene.virtuals[0].material;
    EXPECT_EQ(m.model, MaterialModel::MetallicRoughness);
    EXPECT_NEAR(m.metallic, 0.9f, kTolerance);
    EXPECT_NEAR(m.roughness, 0.4f, kTolerance);
    EXPECT_NEAR(m.albedo.x, 0.5f, kTolerance);
    EXPECT_EQ(m.alphaMode, AlphaMode::Mask);
    EXPECT_EQ(m.alphaCutoff, 0.5f);
    ASSERT_TRUE(m.baseColorTexture && m.normalTexture && m.occlusionTexture);
    EXPECT_EQ(m.occlusionStrength, 1.0f);  // the JSON's texture, at full strength
    EXPECT_EQ(scene.virtuals[0].uvs.size(), scene.virtuals[0].positions.size());
    std::string all;
    for (const std::string& w : scene.warnings) all += w + "\n";
    expectContains(all, {"s.json: virtual[0].material.alpha_mode: \"blend\" is read as \"mask\""});

    // The shapes have texture coordinates: a normal map on a quad stays (its tangents come from them).
    scene = loadScene(sceneWith({{"normal_texture", "marked.png"}}), sceneFile);
    EXPECT_TRUE(scene.virtuals[0].material.normalTexture);
    // A normal map on a mesh without texture coordinates (a "triangles" shape has none): a warning, and no
    // normal map.
    scene = loadScene(
        sceneWith({{"normal_texture", "marked.png"}}, {{"type", "triangles"},
                                                       {"positions", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}},
                                                       {"indices", {{0, 1, 2}}}}),
        sceneFile);
    EXPECT_FALSE(scene.virtuals[0].material.normalTexture);
    all.clear();
    for (const std::string& w : scene.warnings) all += w + "\n";
    expectContains(
        all, {"s.json: virtual[0].material: mesh 'thing' has no texture coordinates (set 0): its normal "
              "texture"});
}

// KHR_materials_emissive_strength, which Debian's Assimp does not read, multiplies the emissive factor
// (docs/scene-format.md: emission is factor x strength).
TEST_F(MeshIoTest, GltfEmissiveStrengthMultipliesTheEmissiveFactor) {
    json document;
    document["materials"] =
        json::array({{{"name", "lamp"},
                      {"emissiveFactor", {1.0, 0.5, 0.25}},
                      {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 40.0}}}}}}});
    document["extensionsUsed"] = {"KHR_materials_emissive_strength"};
    const fs::path file = test::writeQuadGltf(dir_, "lamp", document);
    const std::vector<FileMesh> meshes = loadMeshFile(file, "where", "lamp");
    ASSERT_EQ(meshes.size(), 1u);
    ASSERT_TRUE(meshes[0].material.emission.has_value());
    EXPECT_NEAR(meshes[0].material.emission->x, 40.0f, 1e-4f);
    EXPECT_NEAR(meshes[0].material.emission->y, 20.0f, 1e-4f);
    EXPECT_NEAR(meshes[0].material.emission->z, 10.0f, 1e-4f);
}

}  // namespace
}  // namespace deltagi
