// Environment maps: projections, light extraction (median cut, variance minimization), the prefiltered sky
// through the cones, the path tracer's environment sampling, and the renderer lit by a map. Maps are built in
// code from closed-form skies; the shared light probes are used where present.
#include "core/environment.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <numbers>

#include <gtest/gtest.h>

#include "deltagi/reference.h"
#include "deltagi/renderer.h"
#include "deltagi/scene_io.h"
#include "pipeline/light_extraction.h"
#include "pipeline/sky_light.h"
#include "test_paths.h"
#include "test_scenes.h"

namespace deltagi {
namespace {

namespace fs = std::filesystem;
using test::diffuse;
using test::placed;
constexpr float kPi = std::numbers::pi_v<float>;
using RadianceFn = std::function<glm::vec3(glm::vec3)>;

// Each pixel of a map built from a closed-form sky averages k x k samples, so that a small sun keeps its
// power.
constexpr int kSubsamples = 4;

// An equirectangular map of `radiance`.
Image equirectOf(int width, const RadianceFn& radiance) {
    Image map(width, width / 2, 3);
    for (int y = 0; y < map.height(); ++y)
        for (int x = 0; x < map.width(); ++x) {
            glm::vec3 sum(0.0f);
            for (int j = 0; j < kSubsamples; ++j)
                for (int i = 0; i < kSubsamples; ++i)
                    sum += radiance(equirectDirection((x + (i + 0.5f) / kSubsamples) / map.width(),
                                                      (y + (j + 0.5f) / kSubsamples) / map.height()));
            map.setRgb(x, y, sum / float(kSubsamples * kSubsamples));
        }
    return map;
}

glm::vec3 fromAngles(float elevationDeg, float azimuthDeg) {  // azimuth from -z towards +x, as in the maps
    const float e = glm::radians(elevationDeg), a = glm::radians(azimuthDeg);
    return {std::sin(a) * std::cos(e), std::sin(e), -std::cos(a) * std::cos(e)};
}

float angleDeg(glm::vec3 a, glm::vec3 b) {
    return glm::degrees(std::acos(std::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0f, 1.0f)));
}

// A sky brighter towards the zenith and the sun, a dark ground, and a sun disk of radius sunDeg.
RadianceFn sunnySky(glm::vec3 sun, float sunDeg, float sunRadiance) {
    return [=](glm::vec3 d) {
        if (angleDeg(d, sun) <= sunDeg) return glm::vec3(sunRadiance, 0.9f * sunRadiance, 0.7f * sunRadiance);
        if (d.y < 0.0f) return glm::vec3(0.05f, 0.04f, 0.03f);
        return glm::vec3(0.2f, 0.3f, 0.6f) * (0.5f + d.y) +
               glm::vec3(0.3f) * std::max(glm::dot(d, sun), 0.0f);
    };
}

// The lights within `radiusDeg` of a direction, as one: their summed luminance and luminance-weighted mean
// direction. Median cut splits a sun that holds most of the map's energy among several regions, each with a
// light at its part of the disk.
struct Cluster {
    float power = 0.0f;
    glm::vec3 direction{0.0f};
};
Cluster clusterAround(const std::vector<ExtractedLight>& lights, glm::vec3 centre, float radiusDeg) {
    Cluster c;
    glm::vec3 sum(0.0f);
    for (const ExtractedLight& l : lights)
        if (angleDeg(l.direction, centre) <= radiusDeg) {
            c.power += luminance(l.irradiance);
            sum += luminance(l.irradiance) * l.direction;
        }
    c.direction = glm::length(sum) > 0.0f ? glm::normalize(sum) : sum;
    return c;
}

// Irradiance from the lights on planes facing the 6 axis directions: what the lights do in a render.
std::vector<float> axisIrradiance(const std::vector<ExtractedLight>& lights) {
    std::vector<float> e;
    for (glm::vec3 n : {glm::vec3(1, 0, 0), glm::vec3(-1, 0, 0), glm::vec3(0, 1, 0), glm::vec3(0, -1, 0),
                        glm::vec3(0, 0, 1), glm::vec3(0, 0, -1)}) {
        float sum = 0.0f;
        for (const ExtractedLight& l : lights)
            sum += luminance(l.irradiance) * std::max(glm::dot(n, l.direction), 0.0f);
        e.push_back(sum);
    }
    return e;
}

const ExtractedLight& brightest(const std::vector<ExtractedLight>& lights) {
    return *std::max_element(lights.begin(), lights.end(), [](const auto& a, const auto& b) {
        return luminance(a.irradiance) < luminance(b.irradiance);
    });
}

glm::dvec3 totalOf(const std::vector<ExtractedLight>& lights) {
    glm::dvec3 sum(0.0);
    for (const ExtractedLight& l : lights) sum += glm::dvec3(l.irradiance);
    return sum;
}

constexpr ExtractionMethod kMethods[] = {ExtractionMethod::MedianCut, ExtractionMethod::VarianceMinimization};

// ---- the map ----

TEST(EnvironmentMap, PixelSolidAnglesCoverTheSphereAndDirectionsRoundTrip) {
    EXPECT_NEAR(integrateSphere(Image(64, 32, 3, 1.0f)).x, 4.0 * std::numbers::pi, 1e-9);
    EXPECT_NEAR(glm::distance(equirectDirection(0.5f, 0.5f), glm::vec3(0, 0, -1)), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::distance(equirectDirection(0.75f, 0.5f), glm::vec3(1, 0, 0)), 0.0f, 1e-6f);
    EXPECT_NEAR(equirectDirection(0.3f, 0.0f).y, 1.0f, 1e-6f);
    for (glm::vec2 uv : {glm::vec2(0.1f, 0.2f), glm::vec2(0.6f, 0.7f), glm::vec2(0.95f, 0.45f)}) {
        const glm::vec2 back = equirectUv(equirectDirection(uv.x, uv.y));
        EXPECT_NEAR(back.x, uv.x, 1e-5f);
        EXPECT_NEAR(back.y, uv.y, 1e-5f);
    }
}

TEST(EnvironmentMap, NanInfiniteAndNegativePixelsAreSetToZero) {
    Image map(8, 4, 3, 0.5f);
    map.at(0, 0, 0) = NAN;
    map.at(0, 0, 2) = INFINITY;  // the same pixel: counted once
    map.at(3, 1, 1) = -INFINITY;
    map.at(5, 2, 2) = -0.25f;
    EXPECT_EQ(sanitizeRadiance(map), 3u);
    for (float v : map.data()) EXPECT_TRUE(std::isfinite(v) && v >= 0.0f);
    EXPECT_EQ(map.at(0, 0, 1), 0.5f);  // the pixel's good channels stay
    EXPECT_EQ(map.at(5, 2, 2), 0.0f);
}

// ---- light extraction ----

TEST(LightExtraction, KeepsTheMapsTotalPower) {
    const Image map = equirectOf(256, sunnySky(fromAngles(20.0f, 40.0f), 2.0f, 2000.0f));
    const glm::dvec3 total = integrateSphere(map);
    for (ExtractionMethod method : kMethods)
        for (int count : {1, 5, 16, 64}) {
            const std::vector<ExtractedLight> lights = extractLights(map, count, method);
            EXPECT_EQ(static_cast<int>(lights.size()), count);
            const glm::dvec3 sum = totalOf(lights);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(sum[c], total[c], 1e-5 * total[c]) << count;
        }
    EXPECT_TRUE(extractLights(map, 0, ExtractionMethod::MedianCut).empty());
}

TEST(LightExtraction, PutsTheLightOfASmallSunAtTheSun) {
    const glm::vec3 sun = fromAngles(23.0f, 41.0f);
    const RadianceFn withSun = sunnySky(sun, 1.0f, 50000.0f);
    const Image map = equirectOf(512, withSun);
    const Image noSun = equirectOf(512, sunnySky(sun, 0.0f, 0.0f));
    const double sunPower = luminance(glm::vec3(integrateSphere(map) - integrateSphere(noSun)));
    for (ExtractionMethod method : kMethods) {
        const std::vector<ExtractedLight> lights = extractLights(map, 16, method);
        // The lights at the sun carry its power (and the little sky of their regions), at its centre.
        const Cluster atSun = clusterAround(lights, sun, 2.0f);
        EXPECT_LT(angleDeg(atSun.direction, sun), 0.25f);
        EXPECT_GT(atSun.power, 0.99 * sunPower);
        EXPECT_LT(atSun.power, 1.02 * sunPower);
        EXPECT_LT(angleDeg(brightest(lights).direction, sun), 1.0f);
    }
}

// The fish-eye image of the upper hemisphere, built from the documented convention (looking up, top = -z,
// right = -x), converted to equirectangular, gives the lights of the same sky's equirectangular map.
TEST(LightExtraction, AFisheyeImageAndItsEquirectangularConversionGiveTheSameLights) {
    const glm::vec3 sun = fromAngles(30.0f, -70.0f);
    const RadianceFn sky = sunnySky(sun, 2.0f, 3000.0f);
    const RadianceFn upperHalf = [&](glm::vec3 d) { return d.y > 0.0f ? sky(d) : glm::vec3(0.0f); };
    for (FisheyeProjection::Model model :
         {FisheyeProjection::Model::Equidistant, FisheyeProjection::Model::Equisolid}) {
        FisheyeProjection p{model, {128.0f, 128.0f}, 120.0f, 180.0f};
        Image fisheye(256, 256, 3);
        for (int y = 0; y < 256; ++y)
            for (int x = 0; x < 256; ++x) {
                glm::vec3 sum(0.0f);
                for (int j = 0; j < kSubsamples; ++j)
                    for (int i = 0; i < kSubsamples; ++i) {
                        const glm::vec2 offset =
                            glm::vec2(x + (i + 0.5f) / kSubsamples, y + (j + 0.5f) / kSubsamples) - p.center;
                        const float r = glm::length(offset) / p.radius;
                        if (r > 1.0f) continue;
                        const float theta = model == FisheyeProjection::Model::Equidistant
                                                ? r * 0.5f * kPi
                                                : 2.0f * std::asin(r * std::sin(kPi / 4));
                        const glm::vec2 lateral = r > 0.0f ? offset / glm::length(offset) : glm::vec2(0.0f);
                        // Up the optical axis (+y); image right is -x, image down is +z.
                        sum +=
                            sky({-std::sin(theta) * lateral.x, std::cos(theta), std::sin(theta) * lateral.y});
                    }
                fisheye.setRgb(x, y, sum / float(kSubsamples * kSubsamples));
            }
        const Image converted = equirectFromFisheye(fisheye, p);
        const Image direct = equirectOf(256, upperHalf);
        for (ExtractionMethod method : kMethods) {
            const std::vector<ExtractedLight> a = extractLights(converted, 16, method);
            const std::vector<ExtractedLight> b = extractLights(direct, 16, method);
            ASSERT_EQ(a.size(), b.size());
            const Cluster sunA = clusterAround(a, sun, 4.0f), sunB = clusterAround(b, sun, 4.0f);
            EXPECT_LT(angleDeg(sunA.direction, sun), 0.5f);
            EXPECT_LT(angleDeg(sunA.direction, sunB.direction), 0.5f);
            const glm::dvec3 ta = totalOf(a), tb = totalOf(b);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(ta[c], tb[c], 0.02 * tb[c]);
            const std::vector<float> ea = axisIrradiance(a), eb = axisIrradiance(b);
            for (size_t k = 0; k < ea.size(); ++k) EXPECT_NEAR(ea[k], eb[k], 0.03 * eb[2]) << "plane " << k;
        }
    }
}

TEST(LightExtraction, AMirrorBallImagePutsTheSunWhereItIs) {
    const glm::vec3 sun = fromAngles(35.0f, 150.0f);  // behind the ball, to the side: seen near the rim
    const RadianceFn sky = sunnySky(sun, 2.0f, 3000.0f);
    MirrorBallProjection p{{100.0f, 100.0f}, 96.0f};
    Image ball(200, 200, 3);
    for (int y = 0; y < 200; ++y)
        for (int x = 0; x < 200; ++x) {
            const glm::vec2 q = (glm::vec2(x + 0.5f, y + 0.5f) - p.center) / p.radius;
            if (glm::dot(q, q) > 1.0f) continue;
            const glm::vec3 n(q.x, -q.y, std::sqrt(1.0f - glm::dot(q, q)));
            ball.setRgb(x, y, sky(glm::reflect(glm::vec3(0, 0, -1), n)));
        }
    const std::vector<ExtractedLight> lights =
        extractLights(equirectFromMirrorBall(ball, p), 16, ExtractionMethod::MedianCut);
    EXPECT_LT(angleDeg(clusterAround(lights, sun, 5.0f).direction, sun), 1.0f);
}

// The shared light probe and its fish-eye re-projection of the upper hemisphere
// (shared/data/photos/spruit-sunrise-field) light a scene alike: the same total and the same irradiance on
// planes of every orientation, within the resampling of the two re-projections.
TEST(LightExtraction, TheSharedProbeAndItsFisheyeGiveTheSameLight) {
    const fs::path folder = fs::path(test::kSharedDataDir) / "photos" / "spruit-sunrise-field";
    if (!fs::exists(folder / "probe_equirect_1k.hdr") ||
        !fs::exists(folder / "sky_fisheye_equidistant_512.hdr"))
        GTEST_SKIP() << "needs " << folder.string();
    Image probe = readImage(folder / "probe_equirect_1k.hdr");
    for (int y = probe.height() / 2; y < probe.height(); ++y)  // the fish-eye sees the upper hemisphere only
        for (int x = 0; x < probe.width(); ++x) probe.setRgb(x, y, glm::vec3(0.0f));
    const Image fisheye = readImage(folder / "sky_fisheye_equidistant_512.hdr");
    const Image converted =
        equirectFromFisheye(fisheye, {FisheyeProjection::Model::Equidistant, {256, 256}, 256, 180});
    const std::vector<ExtractedLight> a = extractLights(converted, 16, ExtractionMethod::MedianCut);
    const std::vector<ExtractedLight> b = extractLights(probe, 16, ExtractionMethod::MedianCut);
    const glm::dvec3 ta = totalOf(a), tb = totalOf(b);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ta[c], tb[c], 0.02 * tb[c]);
    const std::vector<float> ea = axisIrradiance(a), eb = axisIrradiance(b);
    for (size_t k = 0; k < ea.size(); ++k) EXPECT_NEAR(ea[k], eb[k], 0.05 * eb[2]) << "plane " << k;
}

// ---- sky light through the cones ----

// Irradiance on a plane under a uniform environment L: pi L. The sky term alone (no extracted lights) must
// give it exactly; extracted lights plus the residual sky approximately (the 9 cones are a quadrature).
TEST(SkyLight, AUniformEnvironmentGivesPiLOnAPlane) {
    const float L = 0.7f;
    const Image map(128, 64, 3, L);
    Options options;
    Material white = diffuse(glm::vec3(1.0f));
    for (glm::vec3 normal : {glm::vec3(0, 1, 0), glm::normalize(glm::vec3(0.3f, 0.9f, -0.4f))}) {
        const SurfacePoint point{glm::vec3(0.0f), normal, normal, &white, constantSurfaceMaterial(white)};
        for (int count : {0, 16}) {
            Environment env;
            env.radiance = map;
            const std::vector<ExtractedLight> lights = extractLights(map, count, ExtractionMethod::MedianCut);
            env.sky = prefilterSky(map, lights);
            const SkyLight sky = traceSkyCones({&point, 1}, env, {}, ShadowMode::Shaded, options);
            double irradiance = kPi * sky.diffuse[0].x;
            for (const ExtractedLight& l : lights)
                irradiance += l.irradiance.x * std::max(glm::dot(l.direction, normal), 0.0f);
            // Measured: 0 lights exact to float rounding; 16 lights within 3%.
            EXPECT_NEAR(irradiance, kPi * L, (count == 0 ? 1e-4 : 0.05) * kPi * L) << count << " lights";
        }
    }
}

TEST(SkyLight, PrefilteringKeepsAUniformMapAndBlursASpotMore) {
    Image map(128, 64, 3, 1.0f);
    EXPECT_NEAR(skyRadiance(prefilterSky(map, {}), glm::vec3(0.2f, 0.5f, 0.3f), 0.3f).y, 1.0f, 1e-5f);
    map.setRgb(32, 20, glm::vec3(1000.0f));  // one bright pixel
    const SkyPyramid sky = prefilterSky(map, {});
    const glm::vec3 spot = equirectDirection(32.5f / 128, 20.5f / 64);
    const float narrow = skyRadiance(sky, spot, std::tan(glm::radians(3.0f))).x;
    const float wide = skyRadiance(sky, spot, std::tan(glm::radians(30.0f))).x;
    EXPECT_GT(narrow, wide);
    EXPECT_GT(wide, 1.0f);
}

// ---- the path tracer ----

Scene planeUnder(const Image& map, float albedo) {
    Scene s;
    s.real.push_back(placed(makeQuad({20.0f, 20.0f}), {0, 0, 0}, diffuse(glm::vec3(albedo)), "plane"));
    s.camera = test::lookAtCamera({0, 2, 2}, {0, 0, 0}, 16, 12, 40.0f);
    s.options.environment.sky = false;
    Environment env;
    env.radiance = map;
    setEnvironment(s, std::move(env));
    return s;
}

glm::dvec3 meanOf(const Image& img) {
    glm::dvec3 sum(0.0);
    for (int y = 0; y < img.height(); ++y)
        for (int x = 0; x < img.width(); ++x) sum += glm::dvec3(img.rgb(x, y));
    return sum / static_cast<double>(img.pixelCount());
}

// A Lambertian plane reflects albedo/pi of its irradiance: albedo L under a uniform map, and for a map with a
// sun the irradiance is the map's cosine-weighted integral over the upper hemisphere (piecewise constant).
TEST(PathTracerEnvironment, APlaneReflectsTheMapsIrradiance) {
    const float albedo = 0.5f;
    const Image uniform(64, 32, 3, 0.7f);
    const Image sunny = equirectOf(64, sunnySky(fromAngles(40.0f, 20.0f), 6.0f, 50.0f));
    for (const Image* map : {&uniform, &sunny}) {
        double irradiance = 0.0;
        for (int y = 0; y < map->height() / 2; ++y)
            for (int x = 0; x < map->width(); ++x) {
                // The exact integral of cos over the pixel: the band's sin^2 difference / 2 times its
                // longitudes.
                const double top = std::sin(equirectRowElevation(y, map->height()));
                const double bottom = std::sin(equirectRowElevation(y + 1, map->height()));
                irradiance += map->rgb(x, y).x * 0.5 * (top * top - bottom * bottom) * 2.0 *
                              std::numbers::pi / map->width();
            }
        const Scene s = planeUnder(*map, albedo);
        ASSERT_EQ(s.lights.size(), 16u);  // extracted, and skipped by the path tracer
        ReferenceOptions o;
        o.samplesPerPixel = 64;
        const double mean = meanOf(renderReference(s, o).with).x;
        // Measured: uniform -0.1%, sunny +0.3%; bound 2% (noise of 64 paths per pixel).
        EXPECT_NEAR(mean, albedo / std::numbers::pi * irradiance,
                    0.02 * albedo / std::numbers::pi * irradiance);
    }
}

// ---- the renderer ----

// Under a uniform sky alone, a box on the floor keeps sky light from the floor around it (its ambient
// occlusion: a negative change), and its top, open to the sky, reflects about albedo L.
TEST(RenderEnvironment, AnObjectUnderTheSkyDarkensTheFloorAroundItsBase) {
    Scene s = test::floorScene();
    s.lights.clear();
    s.virtuals.push_back(placed(makeBox({0.4f, 0.4f, 0.4f}), {0, 0.2f, 0}, diffuse(glm::vec3(0.6f)), "box"));
    s.options.environment.lightCount = 0;
    Environment env;
    env.radiance = Image(64, 32, 3, 1.0f);
    setEnvironment(s, std::move(env));
    const RenderOutput out = render(s);
    for (float v : out.composite.data()) ASSERT_TRUE(std::isfinite(v));
    const glm::ivec2 nearBase = test::project(s.camera, {0.0f, 0.0f, 0.25f});
    const glm::ivec2 far = test::project(s.camera, {0.0f, 0.0f, 0.95f});
    const glm::ivec2 top = test::project(s.camera, {0.0f, 0.4f, 0.0f});
    EXPECT_LT(out.delta.rgb(nearBase.x, nearBase.y).x, -0.05f);
    EXPECT_LT(out.delta.rgb(nearBase.x, nearBase.y).x, out.delta.rgb(far.x, far.y).x);
    EXPECT_NEAR(out.composite.rgb(top.x, top.y).x, 0.6f, 0.1f);
}

}  // namespace
}  // namespace deltagi
