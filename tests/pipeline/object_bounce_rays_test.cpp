// The objects' light on real surfaces by rays (traceObjectBounceRays) against the closed form of a
// uniformly bright sphere: a floor point at distance d under the centre of a sphere of radius r and radiance
// L receives E = pi L (r / d)^2, so the diffuse cones' quantity E / pi is L (r / d)^2. A sphere in front of
// a uniformly bright ceiling of radiance L_c hides the same solid angle of it: the change is
// (L - L_c) (r / d)^2.
#include "pipeline/object_bounce_rays.h"

#include <initializer_list>
#include <span>

#include <gtest/gtest.h>

#include "bright_sphere.h"
#include "core/ray_scene.h"
#include "pipeline/mipmap.h"
#include "pipeline/voxelize.h"
#include "scene/shapes.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

// Each floor point (x = 0.5 + dx, z = 0.5) kCopies times over: the copies' rays are jittered apart (by the
// point's index), so their mean is what is checked (meanOfCopies: the red channel's).
constexpr int kCopies = 16;
std::vector<SurfacePoint> floorPointCopies(std::initializer_list<float> dxs, const Material& floor) {
    std::vector<SurfacePoint> points;
    for (const float dx : dxs)
        for (int c = 0; c < kCopies; ++c) points.push_back(test::floorPoint({0.5f + dx, 0.0f, 0.5f}, floor));
    return points;
}
std::vector<float> meanOfCopies(std::span<const glm::vec3> values) {
    std::vector<float> means(values.size() / kCopies, 0.0f);
    for (size_t k = 0; k < values.size(); ++k) means[k / kCopies] += values[k].x / kCopies;
    return means;
}

// Options with 256 rays per point (the closed forms are checked to 8 %).
Options manyRays() {
    Options options;
    options.diffuse.objectRays = 256;
    return options;
}

// The ray scenes of `s`, whose one object is a sphere of `radius` at `height` over (0.5, 0.5).
struct SphereRays {
    SphereRays(const Scene& s, float radius, float height)
        : realOnly(s, SceneContent::RealOnly),
          all(s, SceneContent::VirtualOnly, &realOnly),
          rays{&realOnly,
               &all,
               {glm::vec3(0.5f - radius, height - radius, 0.5f - radius),
                glm::vec3(0.5f + radius, height + radius, 0.5f + radius)}} {}
    RayScene realOnly;
    RayScene all;
    ShadowRayScenes rays;
};

// The solid angle (times the cosine, over pi: the diffuse cones' measure) of a sphere of `radius` at
// `height` over (0.5, 0.5) seen from the floor point `p`: (r / D)^2 cos, D the distance to its centre and
// cos the angle of the centre from the normal.
float sphereSolidAngle(glm::vec3 p, float radius, float height) {
    const glm::vec3 toCentre = glm::vec3(0.5f, height, 0.5f) - p;
    const float d = glm::length(toCentre);
    return (radius / d) * (radius / d) * (toCentre.y / d);
}

// A sphere of uniform radiance kRadiance (its voxels in the objects' light volume) over a grey floor of
// `floorSize`, and the ray scenes.
struct BrightSphere : test::BrightSphereScene {
    explicit BrightSphere(float floorSize)
        : scene(makeScene(floorSize)), objectLight(light(scene)), traced(scene, kRadius, kHeight) {}
    Scene scene;
    MipVolume objectLight;
    SphereRays traced;
};

TEST(ObjectBounceRays, ABrightSphereLightsTheFloorUnderItAsItsSolidAngle) {
    const BrightSphere bright(2.0f);
    const float radius = BrightSphere::kRadius, height = BrightSphere::kHeight,
                radiance = BrightSphere::kRadiance;
    const Scene& s = bright.scene;
    const MipVolume& objectLight = bright.objectLight;
    const ShadowRayScenes& rays = bright.traced.rays;
    const Options options = manyRays();
    const Material& floor = s.real[0].material;
    const std::vector<SurfacePoint> points = floorPointCopies({0.0f, 0.3f, 0.45f}, floor);
    const std::vector<float> got = meanOfCopies(traceObjectBounceRays(points, objectLight, rays, options));
    // Under the centre: L (r / d)^2. Off to the side the sphere's disk is tilted: E / pi = L (r / D)^2 cos.
    for (size_t k = 0; k < got.size(); ++k) {
        const float expected = radiance * sphereSolidAngle(points[k * kCopies].position, radius, height);
        EXPECT_NEAR(got[k], expected, 0.08f * expected) << k;
    }
    // A floor point with the sphere below its horizon (its back side) gets nothing.
    SurfacePoint below = test::floorPoint({0.5f, height + 0.4f, 0.5f}, floor);
    const SurfacePoint under[] = {below};
    EXPECT_EQ(traceObjectBounceRays(under, objectLight, rays, options)[0], glm::vec3(0.0f));
}

TEST(ObjectBounceRays, ASphereTakesAwayTheCeilingLightItHides) {
    const float radius = 0.15f, height = 0.4f, ceiling = 0.8f, ceilingRadiance = 3.0f;
    const float sphereRadiance = 1.0f;
    Scene s;
    s.real.push_back(
        test::placed(makeQuad({4.0f, 4.0f}), {0.5f, 0.0f, 0.5f}, test::diffuse(glm::vec3(0.5f))));
    s.real.push_back(
        test::placed(makeQuad({4.0f, 4.0f}), {0.5f, ceiling, 0.5f}, test::diffuse(glm::vec3(0.5f))));
    s.virtuals.push_back(
        test::placed(makeSphere(radius, 64), {0.5f, height, 0.5f}, test::diffuse(glm::vec3(0.5f))));
    const VolumeRegion region{glm::vec3(0.0f, -0.05f, 0.0f), 1.0f, 64};
    const VoxelGeometry sphere = voxelize(s.virtuals, region);
    const VoxelGeometry real = voxelize(s.real, region);
    // The objects' volume: the sphere's radiance. The full volume: the ceiling's and the sphere's (the floor
    // is dark); the delta volume (full minus the real scene alone): the sphere's, over the full volume's
    // occupancy.
    const int n = region.resolution;
    Grid3 objects(n), full(n), delta(n);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const size_t i = full.index(x, y, z);
                const float o = sphere.visibility[i].x;
                const float worldY = region.origin.y + (static_cast<float>(y) + 0.5f) * region.voxelSize();
                const float lit = worldY > 0.5f * ceiling ? real.visibility[i].x : 0.0f;
                const float w = std::max(o, real.visibility[i].x);
                objects[i] = glm::vec4(glm::vec3(sphereRadiance * o), o);
                full[i] = glm::vec4(glm::vec3(sphereRadiance * o + ceilingRadiance * lit), w);
                delta[i] = glm::vec4(glm::vec3(sphereRadiance * o), w);
            }
    const MipVolume objectLight = buildMipChain(region, std::move(objects));
    const MipVolume fullLight = buildMipChain(region, std::move(full));
    const MipVolume deltaLight = buildMipChain(region, std::move(delta));
    const SphereRays traced(s, radius, height);
    const ShadowRayScenes& rays = traced.rays;
    const Options options = manyRays();
    const Material& floor = s.real[0].material;
    const std::vector<SurfacePoint> points = floorPointCopies({0.0f, 0.2f}, floor);
    const std::vector<float> change = meanOfCopies(
        traceObjectBounceRays(points, objectLight, rays, options, {}, {&fullLight, &deltaLight}));
    const std::vector<float> own = meanOfCopies(traceObjectBounceRays(points, objectLight, rays, options));
    for (size_t k = 0; k < change.size(); ++k) {
        const float solidAngle = sphereSolidAngle(points[k * kCopies].position, radius, height);
        EXPECT_NEAR(change[k], (sphereRadiance - ceilingRadiance) * solidAngle,
                    0.08f * ceilingRadiance * solidAngle)
            << k;
        // Without the real light the objects' own only.
        EXPECT_NEAR(own[k], sphereRadiance * solidAngle, 0.08f * sphereRadiance * solidAngle) << k;
    }
}

// The difference of two volumes' radiance where a ray lands, with one lookup for both, is the difference of
// their own lookups to the bit: inside either's occupied voxels, where only one has any, and far from both.
TEST(ObjectBounceRays, ARadianceDifferenceIsTheDifferenceOfTheTwoLookups) {
    const VolumeRegion region{glm::vec3(0.0f), 1.0f, 16};
    const int n = region.resolution;
    Grid3 wide(n), narrow(n);
    for (int z = 0; z < n; ++z)
        for (int y = 0; y < n; ++y)
            for (int x = 0; x < n; ++x) {
                const float o = static_cast<float>((x * 7 + y * 3 + z * 5) % 4) / 3.0f;
                wide[wide.index(x, y, z)] = glm::vec4(0.3f * x * o, 0.2f * y * o, 0.1f * z * o, o);
                if (x > 6 && x < 10 && y > 6 && y < 10 && z > 6 && z < 10)
                    narrow[narrow.index(x, y, z)] = glm::vec4(0.7f * o, 0.5f * o, 0.9f * o, o);
            }
    const MipVolume a = buildMipChain(region, std::move(wide));
    const MipVolume b = buildMipChain(region, std::move(narrow));
    int compared = 0, bothNonZero = 0;
    for (int k = 0; k < 400; ++k) {
        RayLanding hit;
        hit.position =
            glm::vec3(static_cast<float>(k % 20) / 19.0f, static_cast<float>((k / 20) % 20) / 19.0f,
                      0.45f + 0.01f * static_cast<float>(k % 7));
        hit.geometricNormal = glm::normalize(glm::vec3(k % 3 - 1.0f, 1.0f, (k / 3) % 3 - 1.0f));
        const glm::vec3 expected = volumeRadianceAt(a, hit) - volumeRadianceAt(b, hit);
        const glm::vec3 got = volumeRadianceDifferenceAt(a, b, hit);
        EXPECT_EQ(got.x, expected.x) << k;
        EXPECT_EQ(got.y, expected.y) << k;
        EXPECT_EQ(got.z, expected.z) << k;
        ++compared;
        if (volumeRadianceAt(b, hit) != glm::vec3(0.0f) && volumeRadianceAt(a, hit) != glm::vec3(0.0f))
            ++bothNonZero;
    }
    EXPECT_EQ(compared, 400);
    EXPECT_GT(bothNonZero, 10);  // the comparison covers points where both volumes have light
}

// A point far from the objects casts all its rays into their bounding sphere's narrow cone, as a near one
// does: the few pixels that cast rays (options.diffuse.object_ray_pixel_stride) each need them, or the filter
// spreads one ray's hit or miss into blotches over the walls. Here the sphere fills a third of its bounding
// sphere's cone (the bounding sphere is its box's), so one ray would hit or miss it: the point's copies,
// jittered apart, would spread by more than their mean.
TEST(ObjectBounceRays, AFarPointCastsEveryRayIntoTheObjectsSmallCone) {
    const BrightSphere bright(5.0f);
    const Options options;  // 16 rays
    const std::vector<SurfacePoint> points = floorPointCopies({1.8f}, bright.scene.real[0].material);
    const std::vector<glm::vec3> got =
        traceObjectBounceRays(points, bright.objectLight, bright.traced.rays, options);
    const float expected = BrightSphere::kRadiance *
                           sphereSolidAngle(points[0].position, BrightSphere::kRadius, BrightSphere::kHeight);
    double mean = 0.0, square = 0.0;
    for (const glm::vec3& v : got) mean += v.x / got.size();
    for (const glm::vec3& v : got) square += (v.x - mean) * (v.x - mean) / got.size();
    EXPECT_NEAR(mean, expected, 0.15 * expected);
    EXPECT_LT(std::sqrt(square), 0.35 * mean);
}

}  // namespace
}  // namespace deltagi
