// Procedural shapes against closed-form areas and volumes, with outward winding and unit normals.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "scene/mesh_io.h"
#include "scene/shapes.h"

namespace deltagi {
namespace {

constexpr double kPi = std::numbers::pi;

glm::dvec3 corner(const TriangleMesh& m, unsigned i) {
    return glm::dvec3(m.positions[i]);
}

double surfaceArea(const TriangleMesh& m) {
    double area = 0.0;
    for (glm::uvec3 t : m.triangles)
        area +=
            0.5 * glm::length(glm::cross(corner(m, t.y) - corner(m, t.x), corner(m, t.z) - corner(m, t.x)));
    return area;
}

// Signed volume by the divergence theorem: positive when the triangles wind outward.
double signedVolume(const TriangleMesh& m) {
    double volume = 0.0;
    for (glm::uvec3 t : m.triangles)
        volume += glm::dot(corner(m, t.x), glm::cross(corner(m, t.y), corner(m, t.z))) / 6.0;
    return volume;
}

// Every normal is unit length and on the same side as its triangles' winding.
void expectConsistentNormals(const TriangleMesh& m) {
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (glm::vec3 n : m.normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
    for (glm::uvec3 t : m.triangles) {
        glm::dvec3 face = glm::cross(corner(m, t.y) - corner(m, t.x), corner(m, t.z) - corner(m, t.x));
        ASSERT_GT(glm::length(face), 0.0) << "degenerate triangle";
        for (unsigned i : {t.x, t.y, t.z}) EXPECT_GT(glm::dot(face, glm::dvec3(m.normals[i])), 0.0);
    }
}

TEST(ShapesTest, BoxHasTwelveOutwardTriangles) {
    TriangleMesh box = makeBox({1, 2, 3});
    EXPECT_EQ(box.triangleCount(), 12u);
    EXPECT_EQ(box.positions.size(), 24u);  // flat faces: 4 vertices each
    expectConsistentNormals(box);
    for (glm::uvec3 t : box.triangles) {
        glm::vec3 centre = (box.positions[t.x] + box.positions[t.y] + box.positions[t.z]) / 3.0f;
        EXPECT_GT(glm::dot(box.normals[t.x], centre), 0.0f);  // points away from the box centre
    }
    EXPECT_NEAR(surfaceArea(box), 2.0 * (1 * 2 + 2 * 3 + 1 * 3), 1e-5);
    EXPECT_NEAR(signedVolume(box), 6.0, 1e-5);
    Bounds3f b = box.bounds();
    EXPECT_EQ(b.min, glm::vec3(-0.5f, -1.0f, -1.5f));
    EXPECT_EQ(b.max, glm::vec3(0.5f, 1.0f, 1.5f));
}

TEST(ShapesTest, SphereAreaAndVolumeApproachClosedForm) {
    // An inscribed UV sphere falls short of 4 pi r^2 by O(1/segments^2): about 0.6% at 32 segments.
    const float r = 2.0f;
    TriangleMesh coarse = makeSphere(r, 32);
    EXPECT_NEAR(surfaceArea(coarse) / (4 * kPi * r * r), 1.0, 0.01);
    TriangleMesh fine = makeSphere(r, 256);
    EXPECT_NEAR(surfaceArea(fine) / (4 * kPi * r * r), 1.0, 2e-4);
    EXPECT_NEAR(signedVolume(fine) / (4.0 / 3.0 * kPi * r * r * r), 1.0, 3e-4);
    expectConsistentNormals(coarse);
    for (size_t i = 0; i < coarse.positions.size(); ++i)
        EXPECT_NEAR(glm::dot(coarse.normals[i], coarse.positions[i] / r), 1.0f,
                    1e-5f);  // exact sphere normals
}

TEST(ShapesTest, QuadFacesUp) {
    TriangleMesh quad = makeQuad({4, 2});
    EXPECT_EQ(quad.triangleCount(), 2u);
    expectConsistentNormals(quad);
    for (glm::vec3 n : quad.normals) EXPECT_EQ(n, glm::vec3(0, 1, 0));
    EXPECT_NEAR(surfaceArea(quad), 8.0, 1e-6);
    Bounds3f b = quad.bounds();
    EXPECT_EQ(b.min, glm::vec3(-2, 0, -1));
    EXPECT_EQ(b.max, glm::vec3(2, 0, 1));
}

TEST(ShapesTest, TorusAreaAndVolumeApproachClosedForm) {
    const float major = 1.0f, minor = 0.25f;
    TriangleMesh torus = makeTorus(major, minor, 256);
    // Pappus: area 4 pi^2 R r, volume 2 pi^2 R r^2; 256 x 128 segments are within 0.1%.
    EXPECT_NEAR(surfaceArea(torus) / (4 * kPi * kPi * major * minor), 1.0, 1e-3);
    EXPECT_NEAR(signedVolume(torus) / (2 * kPi * kPi * major * minor * minor), 1.0, 1e-3);
    expectConsistentNormals(makeTorus(major, minor, 48));
}

TEST(ShapesTest, TrianglesFlatOrSmooth) {
    // Two triangles folded along the x axis by 90 degrees.
    const glm::vec3 positions[] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, -1}};
    const glm::uvec3 triangles[] = {{0, 1, 2}, {0, 1, 3}};
    TriangleMesh flat = makeTriangles(positions, triangles, false);
    EXPECT_EQ(flat.positions.size(), 6u);
    expectConsistentNormals(flat);
    EXPECT_EQ(flat.normals[0], glm::vec3(0, 0, 1));
    EXPECT_EQ(flat.normals[3], glm::vec3(0, 1, 0));

    TriangleMesh smooth = makeTriangles(positions, triangles, true);
    EXPECT_EQ(smooth.positions.size(), 4u);
    glm::vec3 shared = glm::normalize(glm::vec3(0, 1, 1));  // equal areas: the average of both faces
    EXPECT_NEAR(glm::distance(smooth.normals[0], shared), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::distance(smooth.normals[2], glm::vec3(0, 0, 1)), 0.0f, 1e-6f);
}

TEST(MeshTest, CleanMeshRepairsBrokenNormals) {
    TriangleMesh mesh = makeQuad({1, 1});
    mesh.normals[0] = glm::vec3(NAN);
    mesh.normals[1] = glm::vec3(0.0f);
    mesh.normals[2] *= 3.0f;
    EXPECT_EQ(cleanMesh(mesh, "test"), 0u);
    for (glm::vec3 n : mesh.normals) EXPECT_NEAR(glm::distance(n, glm::vec3(0, 1, 0)), 0.0f, 1e-6f);
}

}  // namespace
}  // namespace deltagi
