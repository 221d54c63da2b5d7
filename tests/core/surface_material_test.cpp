// Materials at surface points (surface_material.h): textures, vertex colours, normal maps and alpha masks
// as the G-buffer, the path tracer's hits and voxelization see them.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include <glm/gtc/matrix_transform.hpp>

#include "core/area_lights.h"
#include "core/ray_scene.h"
#include "core/surface_material.h"
#include "deltagi/shapes.h"
#include "pipeline/gbuffer.h"
#include "pipeline/voxelize.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

constexpr float kTolerance = 1e-5f;

void expectNear(glm::vec3 a, glm::vec3 b, float tolerance = kTolerance) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

// A texture of `columns` x `rows` texels from a list, row by row from the top.
std::shared_ptr<const Texture> textureOf(int columns, int rows, std::vector<glm::vec4> texels) {
    return std::make_shared<Texture>(columns, rows, std::move(texels), "test texture");
}

// A red/white checker of `size` x `size` texels, the top-left texel red.
std::shared_ptr<const Texture> checker(int size) {
    std::vector<glm::vec4> texels;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x)
            texels.push_back((x + y) % 2 == 0 ? glm::vec4(1, 0, 0, 1) : glm::vec4(1, 1, 1, 1));
    return textureOf(size, size, std::move(texels));
}

// A 2 x 2 quad at y = 0 (normal +y) with its shape's texture coordinates: u along +x, v along +z.
TriangleMesh texturedQuad(Material material) {
    TriangleMesh quad = makeQuad({2.0f, 2.0f});
    quad.material = std::move(material);
    return quad;
}

// The triangle of `mesh` under world point p (in the y = 0 plane), and p's barycentric coordinates on it.
std::tuple<unsigned, float, float> locate(const TriangleMesh& mesh, glm::vec3 p) {
    for (unsigned t = 0; t < mesh.triangles.size(); ++t) {
        const glm::uvec3 tri = mesh.triangles[t];
        const glm::vec3 a = mesh.positions[tri.x], e1 = mesh.positions[tri.y] - a,
                        e2 = mesh.positions[tri.z] - a;
        const glm::mat2 m(glm::vec2(e1.x, e1.z), glm::vec2(e2.x, e2.z));
        const glm::vec2 uv = glm::inverse(m) * glm::vec2(p.x - a.x, p.z - a.z);
        if (uv.x >= -1e-6f && uv.y >= -1e-6f && uv.x + uv.y <= 1.0f + 1e-6f) return {t, uv.x, uv.y};
    }
    ADD_FAILURE() << "no triangle under the point";
    return {0, 0.0f, 0.0f};
}

SurfaceMaterial materialAt(const TriangleMesh& mesh, glm::vec3 p, float footprint = 0.0f) {
    const auto [t, u, v] = locate(mesh, p);
    glm::vec3 normal(0, 1, 0);
    return surfaceMaterialAt(mesh, t, u, v, footprint, &normal);
}

TEST(SurfaceMaterial, MetallicRoughnessFactorsGiveDiffuseAndF0) {
    Material m;
    m.model = MaterialModel::MetallicRoughness;
    m.albedo = glm::vec3(0.8f, 0.4f, 0.2f);
    m.metallic = 0.25f;
    m.roughness = 0.5f;
    const SurfaceMaterial s = constantSurfaceMaterial(m);
    expectNear(s.diffuse, m.albedo * 0.75f);
    expectNear(s.specular, glm::mix(glm::vec3(0.04f), m.albedo, 0.25f));
    EXPECT_EQ(s.roughness, 0.5f);
    // Phong keeps its albedo and specular as they are.
    Material phong;
    phong.albedo = glm::vec3(0.3f);
    phong.specular = glm::vec3(0.5f);
    expectNear(constantSurfaceMaterial(phong).diffuse, glm::vec3(0.3f));
    expectNear(constantSurfaceMaterial(phong).specular, glm::vec3(0.5f));
}

TEST(SurfaceMaterial, BaseColourTextureIsLookedUpAtTheTexelUnderThePoint) {
    Material m;
    m.albedo = glm::vec3(0.5f);
    // Texels: top-left red, top-right green, bottom-left blue, bottom-right white.
    m.baseColorTexture.texture = textureOf(2, 2, {{1, 0, 0, 1}, {0, 1, 0, 1}, {0, 0, 1, 1}, {1, 1, 1, 1}});
    m.baseColorTexture.sampler.magFilter = TextureFilter::Nearest;
    const TriangleMesh quad = texturedQuad(m);
    // u along +x, v along +z: the image's top-left is at (-1, 0, -1).
    expectNear(materialAt(quad, {-0.5f, 0, -0.5f}).diffuse, glm::vec3(0.5f, 0, 0));
    expectNear(materialAt(quad, {0.5f, 0, -0.5f}).diffuse, glm::vec3(0, 0.5f, 0));
    expectNear(materialAt(quad, {-0.5f, 0, 0.5f}).diffuse, glm::vec3(0, 0, 0.5f));
    expectNear(materialAt(quad, {0.5f, 0, 0.5f}).diffuse, glm::vec3(0.5f));
}

TEST(SurfaceMaterial, FootprintSelectsTheTexturesMeanOverIt) {
    Material m;
    m.albedo = glm::vec3(1.0f);
    m.baseColorTexture.texture = checker(64);
    const TriangleMesh quad = texturedQuad(m);
    // A footprint of the whole quad: the checker's mean, pink; none: a texel, red or white.
    expectNear(materialAt(quad, {0.1f, 0, 0.1f}, 2.0f).diffuse, glm::vec3(1.0f, 0.5f, 0.5f), 1e-3f);
    // The first texel's centre: texture coordinates 0.5/64 over a quad 2 wide.
    const glm::vec3 texel = materialAt(quad, {1.0f / 64 - 1.0f, 0, 1.0f / 64 - 1.0f}).diffuse;
    expectNear(texel, glm::vec3(1, 0, 0), 1e-3f);
}

TEST(SurfaceMaterial, VertexColoursMultiplyTheAlbedo) {
    TriangleMesh quad = texturedQuad(test::diffuse(glm::vec3(0.5f)));
    quad.colors.assign(quad.positions.size(), glm::vec3(1.0f, 0.5f, 0.0f));
    expectNear(materialAt(quad, {0.3f, 0, -0.2f}).diffuse, glm::vec3(0.5f, 0.25f, 0.0f));
}

TEST(SurfaceMaterial, MetallicRoughnessTextureReadsBlueAndGreen) {
    Material m;
    m.model = MaterialModel::MetallicRoughness;
    m.albedo = glm::vec3(1.0f, 0.5f, 0.25f);
    m.metallic = 1.0f;
    m.roughness = 1.0f;
    m.metallicRoughnessTexture.texture = textureOf(1, 1, {{0.0f, 0.3f, 0.5f, 1.0f}});
    const SurfaceMaterial s = materialAt(texturedQuad(m), {0, 0, 0});
    EXPECT_NEAR(s.roughness, 0.3f, kTolerance);
    expectNear(s.diffuse, m.albedo * 0.5f);
    expectNear(s.specular, glm::mix(glm::vec3(0.04f), m.albedo, 0.5f));
}

// The maps of one material are looked up together (one Texture::Lookup for maps of one size, texture
// coordinate set and sampler): each still reads its own texels where its size or sampler differs from the
// map before it.
TEST(SurfaceMaterial, EachMapIsReadWithItsOwnSizeAndSampler) {
    Material m;
    m.model = MaterialModel::MetallicRoughness;
    m.metallic = 1.0f;
    m.roughness = 1.0f;
    m.albedo = glm::vec3(1.0f);
    m.baseColorTexture.texture = checker(8);
    m.baseColorTexture.sampler.magFilter = TextureFilter::Nearest;
    // Of the base colour's size, bilinear: its own weights, not the nearest texel's.
    std::vector<glm::vec4> ramp;
    for (int i = 0; i < 64; ++i) ramp.emplace_back(0.0f, (i % 8) / 7.0f, 1.0f - (i / 8) / 7.0f, 1.0f);
    m.metallicRoughnessTexture.texture = textureOf(8, 8, ramp);
    // Another size.
    m.emissiveTexture.texture = checker(3);
    m.emission = glm::vec3(1.0f);
    const glm::vec3 p(0.13f, 0.0f, -0.41f);
    const SurfaceMaterial s = materialAt(texturedQuad(m), p);
    const glm::vec2 uv((p.x + 1.0f) / 2.0f, (p.z + 1.0f) / 2.0f);
    const glm::vec4 base = m.baseColorTexture.sample(uv, 0.0f);
    const glm::vec4 metallicRoughness = m.metallicRoughnessTexture.sample(uv, 0.0f);
    EXPECT_NEAR(s.roughness, metallicRoughness.y, kTolerance);
    expectNear(s.diffuse, glm::vec3(base) * (1.0f - metallicRoughness.z));
    expectNear(s.emission, glm::vec3(m.emissiveTexture.sample(uv, 0.0f)));
    EXPECT_NE(metallicRoughness.y, m.metallicRoughnessTexture.texture->texel(0, 4, 2).y);  // blended
}

// MTL's scalar maps: map_Pr multiplies the roughness, map_Ns the Phong exponent.
TEST(SurfaceMaterial, MtlRoughnessAndShininessMapsScaleTheLobe) {
    Material m;
    m.specular = glm::vec3(0.5f);
    m.roughness = 0.5f;  // exponent 6
    m.roughnessTexture.texture = textureOf(1, 1, {{0.4f, 0.4f, 0.4f, 1.0f}});
    EXPECT_NEAR(materialAt(texturedQuad(m), {0, 0, 0}).roughness, 0.2f, kTolerance);
    m.roughnessTexture = {};
    m.shininessTexture.texture = textureOf(1, 1, {{0.5f, 0.5f, 0.5f, 1.0f}});
    EXPECT_NEAR(materialAt(texturedQuad(m), {0, 0, 0}).phongExponent(), 3.0f, 1e-4f);
}

// A tangent-space normal map on the quad (normal +y, texture u along +x, v along +z): red tilts the normal
// towards +u, green towards the image's top (-v: -z), as glTF defines it; with the shape's texture
// coordinates alone (tangents derived from them) and with tangents given.
TEST(SurfaceMaterial, NormalMapTiltsTheNormalInTheTangentFrame) {
    for (bool givenTangents : {false, true}) {
        SCOPED_TRACE(givenTangents ? "given tangents" : "tangents from texture coordinates");
        Material m;
        m.normalTexture.texture = textureOf(1, 1, {{1.0f, 0.5f, 1.0f, 1.0f}});  // (1, 0, 1) in tangent space
        TriangleMesh quad = texturedQuad(m);
        if (givenTangents) quad.tangents.assign(quad.positions.size(), glm::vec4(1, 0, 0, 1));
        auto mapped = [&](glm::vec4 texel, float scale) {
            quad.material.normalTexture.texture = textureOf(1, 1, {texel});
            quad.material.normalScale = scale;
            const auto [t, u, v] = locate(quad, {0.2f, 0, 0.3f});
            glm::vec3 n(0, 1, 0);
            surfaceMaterialAt(quad, t, u, v, 0.0f, &n);
            return n;
        };
        expectNear(mapped({1.0f, 0.5f, 1.0f, 1}, 1.0f), glm::normalize(glm::vec3(1, 1, 0)));
        expectNear(mapped({0.5f, 1.0f, 1.0f, 1}, 1.0f), glm::normalize(glm::vec3(0, 1, -1)));
        expectNear(mapped({0.5f, 0.5f, 1.0f, 1}, 1.0f), glm::vec3(0, 1, 0));
        // The scale multiplies x and y.
        expectNear(mapped({1.0f, 0.5f, 1.0f, 1}, 0.5f), glm::normalize(glm::vec3(0.5f, 1, 0)));
    }
}

// Alpha-masked surfaces are not there where alpha < cutoff: rays pass through to what lies behind.
TEST(SurfaceMaterial, AlphaMaskLetsRaysThroughTheCutAwayTexels) {
    Scene scene;
    Material leaf;
    leaf.alphaMode = AlphaMode::Mask;
    leaf.alphaCutoff = 0.5f;
    leaf.baseColorTexture.texture = textureOf(2, 1, {{1, 1, 1, 1}, {1, 1, 1, 0}});  // left kept, right cut
    leaf.baseColorTexture.sampler.magFilter = TextureFilter::Nearest;
    scene.real.push_back(test::placed(makeQuad({2.0f, 2.0f}), {0, 1, 0}, leaf, "leaf"));
    scene.real.push_back(
        test::placed(makeQuad({2.0f, 2.0f}), {0, 0, 0}, test::diffuse(glm::vec3(0.5f)), "floor"));
    const RayScene rays(scene, SceneContent::RealOnly);
    const glm::vec3 down(0, -1, 0);
    EXPECT_NEAR(rays.intersect({-0.5f, 2, 0}, down).position.y, 1.0f, 1e-5f);  // the kept half
    EXPECT_NEAR(rays.intersect({0.5f, 2, 0}, down).position.y, 0.0f, 1e-5f);   // through the cut half
    EXPECT_TRUE(rays.occluded({-0.5f, 2, 0}, down, 0.0f, 1.5f));
    EXPECT_FALSE(rays.occluded({0.5f, 2, 0}, down, 0.0f, 1.5f));
    // An opaque material ignores alpha.
    scene.real[0].material.alphaMode = AlphaMode::Opaque;
    const RayScene opaque(scene, SceneContent::RealOnly);
    EXPECT_NEAR(opaque.intersect({0.5f, 2, 0}, down).position.y, 1.0f, 1e-5f);
}

// The camera's G-buffer filters a texture over each pixel: a fine checker far away is its mean.
TEST(SurfaceMaterial, GBufferFiltersTexturesOverThePixel) {
    Scene scene;
    Material m;
    m.albedo = glm::vec3(1.0f);
    m.baseColorTexture.texture = checker(256);
    scene.real.push_back(test::placed(makeQuad({2.0f, 2.0f}), {0, 0, 0}, m, "floor"));
    scene.camera = test::lookAtCamera({0, 3, 0.01f}, {0, 0, 0}, 16, 16, 40.0f);
    const RayScene rays(scene, SceneContent::RealOnly);
    const SurfacePoints points = renderRealSurfaces(scene.camera, rays);
    // 16 pixels over about 2.2 world units: each pixel covers ~18 texels of the 256 over 2.
    for (const SurfacePoint& p : points) {
        if (!p.valid()) continue;
        expectNear(p.surface.diffuse, glm::vec3(1.0f, 0.5f, 0.5f), 0.05f);
    }
}

// Voxelization averages the textured albedo over each voxel's surface: a fine red/white checker floor
// reflects pink into the volumes, a coarse one its texels' colours voxel by voxel.
TEST(SurfaceMaterial, VoxelsAverageTheTexturedAlbedo) {
    const VolumeRegion region{glm::vec3(-1.0f, -1.0f, -1.0f), 2.0f, 4};
    auto voxelAlbedo = [&](int checks, int x, int z) {
        Material m;
        m.albedo = glm::vec3(1.0f);
        m.baseColorTexture.texture = checker(checks);
        m.baseColorTexture.sampler.magFilter = TextureFilter::Nearest;
        std::vector<TriangleMesh> meshes{test::placed(makeQuad({2.0f, 2.0f}), {0, 0.25f, 0}, m, "floor")};
        const VoxelGeometry g = voxelize(meshes, region, false, true);
        // The albedo is kept per surface voxel.
        const auto at = std::find(g.surfaceVoxels.begin(), g.surfaceVoxels.end(),
                                  static_cast<uint32_t>(g.visibility.index(x, 2, z)));
        EXPECT_NE(at, g.surfaceVoxels.end());
        return at == g.surfaceVoxels.end() ? glm::vec3(-1.0f) : g.albedo[at - g.surfaceVoxels.begin()];
    };
    expectNear(voxelAlbedo(64, 1, 2), glm::vec3(1.0f, 0.5f, 0.5f), 0.02f);
    // 4 x 4 checks over the 4 x 4 voxels: each voxel holds one check (voxel (0, 0) the image's top-left).
    expectNear(voxelAlbedo(4, 0, 0), glm::vec3(1, 0, 0), 1e-3f);
    expectNear(voxelAlbedo(4, 1, 0), glm::vec3(1, 1, 1), 1e-3f);
}

// An emissive texture scales each emitting triangle's radiance by its mean over the triangle: a panel whose
// left half is black emits from its right half only, and the area lights sample only there.
TEST(SurfaceMaterial, EmissiveTexturesScaleTheAreaLightsTriangles) {
    Scene scene;
    Material panel;
    panel.albedo = glm::vec3(0.0f);
    panel.emission = glm::vec3(2.0f);
    panel.emissiveTexture.texture = textureOf(2, 1, {{0, 0, 0, 1}, {1, 1, 1, 1}});
    panel.emissiveTexture.sampler.magFilter = TextureFilter::Nearest;
    panel.emissiveTexture.sampler.minFilter = TextureFilter::Nearest;
    // Two unit-by-two quads side by side along x.
    for (int i = 0; i < 2; ++i) {
        TriangleMesh half = makeQuad({1.0f, 2.0f});
        // Texture coordinates of the left or the right half of the image over the whole quad.
        for (glm::vec2& uv : half.uvs) uv.x = 0.25f + 0.5f * static_cast<float>(i);
        scene.real.push_back(test::placed(half, {static_cast<float>(i), 0, 0}, panel, "panel"));
    }
    const AreaLights lights(scene, SceneContent::RealOnly);
    for (float u : {0.1f, 0.4f, 0.6f, 0.9f}) {
        const AreaLightSample s = lights.sample(u, 0.3f, 0.6f);
        EXPECT_GT(s.position.x, 0.4f) << "sampled the black panel at " << u;
        expectNear(s.radiance, glm::vec3(2.0f));
    }
    EXPECT_NEAR(lights.pdfArea(glm::vec3(2.0f)), 0.5f, 1e-5f);  // one unit panel of two holds all the power
}

}  // namespace
}  // namespace deltagi
