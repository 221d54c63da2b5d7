// Mesh files through Assimp (mesh_io.cpp) and the clean-up of meshes (mesh.cpp): per-vertex attributes
// (texture coordinates, tangents, vertex colours) as read, as cleaned and as transformed.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "deltagi/error.h"
#include "deltagi/transforms.h"
#include "image_encode.h"
#include "mesh_io.h"
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
        dir_ = fs::temp_directory_path() / ("deltagi_mesh_io_" + std::to_string(getpid()) + "_" + info->name());
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
    const fs::path ply = write("coloured.ply",
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
    const fs::path wide = write("wide-uv.obj",
                                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt -3 0\nvt 7.5 0\nvt 0 12\nf 1/1 2/2 3/3\n");
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

}  // namespace
}  // namespace deltagi
