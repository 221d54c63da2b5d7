// Microbenchmarks of the pipeline's hot kernels (Google Benchmark): voxelization, light injection, mipmaps
// and the cone marcher. Items per second are triangles, RSM texels, voxels and cone samples (steps). Run:
//   build/bench/deltagi_microbench [--benchmark_filter=Cone] [--benchmark_repetitions=5]
// The whole-frame figures come from `deltagi bench` (docs in README "Performance").
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <string>

#include <tbb/task_arena.h>
#include <glm/gtc/matrix_transform.hpp>

#include "core/parallel.h"
#include "core/ray_scene.h"
#include "deltagi/renderer.h"
#include "deltagi/transforms.h"
#include "pipeline/cone_trace.h"
#include "pipeline/denoise.h"
#include "pipeline/gbuffer.h"
#include "pipeline/inject.h"
#include "pipeline/mipmap.h"
#include "pipeline/object_volumes.h"
#include "pipeline/reflective_shadow_map.h"
#include "pipeline/voxelize.h"
#include "scene/shapes.h"

namespace deltagi {
namespace {

// A floor with a ball on it, under a point light: the shape of the paper's scenes at small cost.
struct KernelScene {
    Scene scene;
    VolumeRegion region;

    explicit KernelScene(int resolution, int sphereSegments = 96) {
        TriangleMesh floor = makeQuad({2.0f, 2.0f});
        floor.name = "floor";
        scene.real.push_back(std::move(floor));
        TriangleMesh ball = makeSphere(0.3f, sphereSegments);
        for (glm::vec3& p : ball.positions) p.y += 0.3f;
        ball.name = "ball";
        scene.virtuals.push_back(std::move(ball));
        Light light;
        light.position = {0.3f, 1.5f, 0.2f};
        light.intensity = 2.0f;
        scene.lights.push_back(light);
        region = {glm::vec3(-1.0f, -0.2f, -1.0f), 2.0f, resolution};
    }
};

void BM_Voxelize(benchmark::State& state) {
    const KernelScene k(128, static_cast<int>(state.range(0)));
    for (auto _ : state) benchmark::DoNotOptimize(voxelize(k.scene.virtuals, k.region));
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(k.scene.virtuals[0].triangleCount()));
    state.counters["triangles"] = static_cast<double>(k.scene.virtuals[0].triangleCount());
}
BENCHMARK(BM_Voxelize)->Arg(96)->Arg(316)->Unit(benchmark::kMillisecond);  // 9k and 100k triangles

void BM_Inject(benchmark::State& state) {
    const KernelScene k(128);
    const RayScene realOnly(k.scene, SceneContent::RealOnly);
    const RayScene all(k.scene, SceneContent::VirtualOnly, &realOnly);
    const std::vector<ReflectiveShadowMap> rsms = {
        renderReflectiveShadowMap(all, k.scene.lights[0], k.region, static_cast<int>(state.range(0)))};
    const VoxelGeometry scene = voxelize(k.scene.real, k.region),
                        objects = voxelize(k.scene.virtuals, k.region);
    const VoxelGeometry* both[] = {&scene, &objects};
    for (auto _ : state) benchmark::DoNotOptimize(injectLight(rsms, k.region, both));
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(rsms[0].texels.size()));
}
BENCHMARK(BM_Inject)->Arg(512)->Unit(benchmark::kMillisecond);

void BM_Mipmap(benchmark::State& state) {
    const int n = static_cast<int>(state.range(0));
    const KernelScene k(n);
    const VoxelGeometry g = voxelize(k.scene.virtuals, k.region);
    for (auto _ : state) benchmark::DoNotOptimize(buildMipChain(k.region, g.visibility.clone()));
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(g.visibility.size()));
}
BENCHMARK(BM_Mipmap)->Arg(64)->Arg(128)->Arg(256)->Unit(benchmark::kMillisecond);

// Stages 1, 3 and 4 of a frame in which the 100k-triangle ball moves a little (a circle of one voxel's
// radius, 1/16 turn per frame, as in `deltagi bench`), on the volumes kept from the frame before
// (ObjectVolumes, as FrameRenderer runs them): one stage's time per benchmark (manual time; the RSM update
// between stages is not counted). BM_Voxelize/316, BM_Inject and BM_Mipmap/128 above do the same work over
// whole volumes.
enum class FrameStage { Voxelize, Inject, Mipmap };
void BM_MovingObjectFrame(benchmark::State& state, FrameStage stage) {
    KernelScene k(128, 316);
    const RayScene realOnly(k.scene, SceneContent::RealOnly);
    const VoxelGeometry sceneGeometry = voxelize(k.scene.real, k.region);
    const Light& light = k.scene.lights[0];
    const std::vector<ReflectiveShadowMap> sceneRsms = {
        renderReflectiveShadowMap(realOnly, light, k.region, 512)};
    const VoxelGeometry* alone[] = {&sceneGeometry};
    const Grid3 sceneLight = injectLight(sceneRsms, k.region, alone);
    const std::vector<glm::vec3> original = k.scene.virtuals[0].positions;
    ObjectVolumes volumes;
    int frame = 0;
    using Clock = std::chrono::steady_clock;
    auto runFrame = [&]() {
        const float angle = 2.0f * std::numbers::pi_v<float> * static_cast<float>(frame++) / 16.0f;
        const glm::vec3 offset =
            k.region.voxelSize() * glm::vec3(std::cos(angle) - 1.0f, 0.0f, std::sin(angle));
        for (size_t v = 0; v < original.size(); ++v) k.scene.virtuals[0].positions[v] = original[v] + offset;
        const RayScene all(k.scene, SceneContent::VirtualOnly, &realOnly);
        const Bounds3f bounds = k.scene.virtuals[0].bounds();
        const auto t0 = Clock::now();
        volumes.voxelize(k.scene.virtuals, k.region);
        const auto t1 = Clock::now();
        const std::vector<RsmUpdate> updates = {traceRsmUpdate(sceneRsms[0], all, light, k.region, bounds)};
        const auto t2 = Clock::now();
        volumes.inject({sceneGeometry, sceneRsms, sceneLight}, updates);
        const auto t3 = Clock::now();
        volumes.mipmap();
        const auto t4 = Clock::now();
        const auto [begin, end] = stage == FrameStage::Voxelize ? std::pair{t0, t1}
                                  : stage == FrameStage::Inject ? std::pair{t2, t3}
                                                                : std::pair{t3, t4};
        return std::chrono::duration<double>(end - begin).count();
    };
    runFrame();  // the first frame computes everything
    for (auto _ : state) state.SetIterationTime(runFrame());
    state.counters["voxels_redone"] = static_cast<double>(volumes.injectedBox().count());
}
BENCHMARK_CAPTURE(BM_MovingObjectFrame, Voxelize, FrameStage::Voxelize)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MovingObjectFrame, Inject, FrameStage::Inject)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_MovingObjectFrame, Mipmap, FrameStage::Mipmap)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

// A closed box (the Cornell box's shape) seen from inside by a 640 x 480 camera: every camera ray hits.
struct BoxView {
    Scene scene;
    Camera camera;
    BoxView() {
        TriangleMesh room = makeBox(glm::vec3(1.0f));
        room.name = "room";
        scene.real.push_back(std::move(room));
        camera.setFieldOfView(60.0);
        camera.worldFromCamera = lookAtPose({0.0f, 0.0f, 0.45f}, {0.0f, 0.0f, 0.0f});
    }
};

// The real half of the G-buffer, redone every frame while the camera moves: one camera ray per pixel of
// BoxView's image.
void BM_RealSurfaces(benchmark::State& state) {
    const BoxView view;
    const RayScene realOnly(view.scene, SceneContent::RealOnly);
    const Camera& camera = view.camera;
    SurfacePoints real;  // reused, as FrameRenderer does
    for (auto _ : state) {
        renderRealSurfaces(camera, realOnly, real);
        benchmark::DoNotOptimize(real.data());
    }
    state.SetItemsProcessed(state.iterations() * camera.width * camera.height);
}
BENCHMARK(BM_RealSurfaces)->Unit(benchmark::kMillisecond);

// The edge-aware filter (denoiseInto) over the real G-buffer of BoxView at 640 x 480, 3 channels a pixel:
// Args(stride, kept) with stride > 1 are a relit pass (radius 1, the pixels between the samples
// interpolated): kept 1 a warm frame's, with the stride's kept plan built before timing; kept 0 a moving
// camera's, without one. Args(1, 0) the objects' own pass (every pixel, radius 2) over a rectangle of 160 x
// 150 pixels, about what the benchmark scene's statue covers. Items are the pixels filtered.
// The values: a smooth change with a little noise, zero in a corner; with `shadowChange`, zero but for a disk
// a sixth of the image's height across, as a relit shadow pass's change (most cells all zero).
void edgeAwareFilter(benchmark::State& state, bool shadowChange) {
    const int stride = static_cast<int>(state.range(0));
    const bool kept = state.range(1) != 0;
    const BoxView view;
    const RayScene realOnly(view.scene, SceneContent::RealOnly);
    const Camera& camera = view.camera;
    const SurfacePoints points = renderRealSurfaces(camera, realOnly);
    const int w = camera.width, h = camera.height;
    std::vector<float> input(static_cast<size_t>(w) * h * 3);
    for (size_t i = 0; i < input.size(); ++i) {
        const int x = static_cast<int>((i / 3) % w), y = static_cast<int>((i / 3) / w);
        const bool zero = shadowChange ? std::hypot(x - w / 2, y - h / 2) > h / 12.0f : x < w / 8;
        input[i] = zero ? 0.0f : 0.1f + 0.05f * std::sin(0.001f * i) + 0.01f * ((i * 7919) % 13);
    }
    DenoiseSettings s;
    PixelRect rect{0, 0, w, h};
    InterpolationPlan plan;
    plan.surfaces = points;
    if (stride > 1) {
        s.radius = 1;
        s.stride = stride;
        s.interpolate = true;
        if (kept) s.plan = &plan;
    } else {
        rect = {240, 160, 400, 310};
    }
    const glm::vec3 eye = camera.worldFromCamera[3];
    const float pixelAngle = 1.0f / camera.fy;
    std::vector<float> values = input;
    denoiseInto(values, 3, points, w, h, eye, pixelAngle, s, nullptr, &rect);  // builds the plan
    for (auto _ : state) {
        state.PauseTiming();
        values = input;
        state.ResumeTiming();
        denoiseInto(values, 3, points, w, h, eye, pixelAngle, s, nullptr, &rect);
        benchmark::DoNotOptimize(values.data());
    }
    state.SetItemsProcessed(state.iterations() * (rect.x1 - rect.x0) * (rect.y1 - rect.y0));
}
void BM_EdgeAwareFilter(benchmark::State& state) {
    edgeAwareFilter(state, false);
}
void BM_EdgeAwareFilterShadowChange(benchmark::State& state) {
    edgeAwareFilter(state, true);
}
BENCHMARK(BM_EdgeAwareFilter)
    ->Args({1, 0})
    ->Args({2, 1})
    ->Args({4, 1})
    ->Args({8, 1})
    ->Args({16, 1})
    ->Args({2, 0})
    ->Args({4, 0})
    ->Args({8, 0})
    ->Args({16, 0})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EdgeAwareFilterShadowChange)
    ->Args({2, 1})
    ->Args({2, 0})
    ->Args({4, 0})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// The real scene's reflective shadow map, made anew whenever the light changes (a light camera's every
// frame): a spot light under the ceiling of a closed box of the Cornell box's size pointing down, its cone
// nearly a hemisphere, the cube map of the benchmark scene's light (6 x 384^2 texels at 128^3; the faces and
// texels outside the cone are passed over). Items are the texels made.
void BM_ReflectiveShadowMap(benchmark::State& state) {
    Scene scene;
    TriangleMesh room = makeBox(glm::vec3(0.556f));
    for (glm::vec3& p : room.positions) p += glm::vec3(0.278f);
    room.name = "room";
    scene.real.push_back(std::move(room));
    Light spot;
    spot.type = Light::Type::Spot;
    spot.position = {0.278f, 0.4878f, 0.2795f};
    spot.direction = {0.0f, -1.0f, 0.0f};
    spot.innerAngleDeg = 60.0f;
    spot.outerAngleDeg = 85.0f;
    spot.radius = 0.06f;
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const VolumeRegion region{glm::vec3(-0.022f, -0.0256f, -0.0204f), 0.6f, 128};
    size_t texels = 0;
    for (auto _ : state) {
        const ReflectiveShadowMap rsm = renderReflectiveShadowMap(realOnly, spot, region, 384);
        texels = rsm.texels.size();
        benchmark::DoNotOptimize(rsm.texels.data());
    }
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(texels));
    state.counters["texels"] = static_cast<double>(texels);
}
BENCHMARK(BM_ReflectiveShadowMap)->Unit(benchmark::kMillisecond);

// The objects' half of the G-buffer, redone every frame: the 100k-triangle ball filling about a third of a
// 640 x 480 image, its pixels and silhouettes with 2 x 2 sub-samples (samples_per_pixel 4, the default).
void BM_ObjectSurfaces(benchmark::State& state) {
    const KernelScene k(128, 316);
    const RayScene realOnly(k.scene, SceneContent::RealOnly);
    const RayScene all(k.scene, SceneContent::VirtualOnly, &realOnly);
    Camera camera;
    camera.setFieldOfView(45.0);
    camera.worldFromCamera = lookAtPose({0.0f, 0.6f, 1.4f}, {0.0f, 0.3f, 0.0f});
    GBuffer gbuffer;  // reused, as FrameRenderer does
    for (auto _ : state) {
        renderObjectSurfaces(camera, all, k.scene.virtuals[0].bounds(), 4, gbuffer);
        benchmark::DoNotOptimize(gbuffer.object.data());
    }
    state.counters["samples"] = static_cast<double>(gbuffer.objectSamples.points.size());
}
BENCHMARK(BM_ObjectSurfaces)->Unit(benchmark::kMillisecond);

// A base colour and a normal texture of the glTF example vase's size and encodings (512 x 512, 8-bit; sRGB
// and linear), procedural: a checker of 32 squares and a ripple.
struct VaseLikeMaps {
    std::shared_ptr<const Texture> baseColour, normal;
    VaseLikeMaps() {
        constexpr int kSize = 512;
        std::vector<uint8_t> colour(kSize * kSize * 4), normals(kSize * kSize * 4);
        for (int y = 0; y < kSize; ++y)
            for (int x = 0; x < kSize; ++x) {
                uint8_t* c = &colour[(static_cast<size_t>(y) * kSize + x) * 4];
                const bool white = ((x / 16) + (y / 16)) % 2 == 0;
                c[0] = 230, c[1] = white ? 230 : 40, c[2] = white ? 230 : 40, c[3] = 255;
                uint8_t* n = &normals[(static_cast<size_t>(y) * kSize + x) * 4];
                const float slope = 0.3f * std::sin(static_cast<float>(x) * 0.2f);
                n[0] = static_cast<uint8_t>(std::lround(127.5f + 127.5f * slope));
                n[1] = 128, n[2] = 240, n[3] = 255;
            }
        baseColour = std::make_shared<const Texture>(kSize, kSize, std::move(colour), TextureEncoding::Srgb,
                                                     "checker");
        normal = std::make_shared<const Texture>(kSize, kSize, std::move(normals), TextureEncoding::Linear,
                                                 "ripple");
    }
};

// The same with the vase-like base colour and normal textures on the ball: the texture lookups' share of
// the G-buffer.
void BM_ObjectSurfacesTextured(benchmark::State& state) {
    KernelScene k(128, 316);
    const VaseLikeMaps maps;
    Material& m = k.scene.virtuals[0].material;
    m.baseColorTexture.texture = maps.baseColour;
    m.normalTexture.texture = maps.normal;
    const RayScene realOnly(k.scene, SceneContent::RealOnly);
    const RayScene all(k.scene, SceneContent::VirtualOnly, &realOnly);
    Camera camera;
    camera.setFieldOfView(45.0);
    camera.worldFromCamera = lookAtPose({0.0f, 0.6f, 1.4f}, {0.0f, 0.3f, 0.0f});
    GBuffer gbuffer;
    for (auto _ : state) {
        renderObjectSurfaces(camera, all, k.scene.virtuals[0].bounds(), 4, gbuffer);
        benchmark::DoNotOptimize(gbuffer.object.data());
    }
}
BENCHMARK(BM_ObjectSurfacesTextured)->Unit(benchmark::kMillisecond);

// The material lookups of the textured benchmark frame (examples/bench-cornell-torus-textured.json) alone:
// its torus (99,856 triangles, no tangents: the normal map's frame from the texture coordinates) seen by its
// camera through 2 x 2 sub-samples per pixel, each hit looked up as the G-buffer does (lookUpMaterial with
// the sub-sample's footprint), with procedural 512 x 512 8-bit textures of the vase's sizes and encodings (a
// sRGB base colour, a linear normal map): the argument says which, 1 the base colour, 2 the normal map, 3
// both. One thread; items are lookups (about 72,000 per frame).
void BM_MaterialLookups(benchmark::State& state) {
    Scene scene;
    TriangleMesh torus = makeTorus(0.08f, 0.035f, 316);
    const glm::mat4 place = glm::translate(glm::mat4(1.0f), glm::vec3(0.41f, 0.115f, 0.15f)) *
                            glm::rotate(glm::mat4(1.0f), glm::radians(90.0f), glm::vec3(1, 0, 0));
    for (glm::vec3& p : torus.positions) p = glm::vec3(place * glm::vec4(p, 1.0f));
    for (glm::vec3& n : torus.normals) n = glm::normalize(glm::vec3(place * glm::vec4(n, 0.0f)));
    const VaseLikeMaps vase;
    torus.material.model = MaterialModel::MetallicRoughness;
    torus.material.roughness = 0.4f;
    const int64_t maps = state.range(0);  // 1: the base colour, 2: the normal map, 3: both
    if (maps & 1) torus.material.baseColorTexture.texture = vase.baseColour;
    if (maps & 2) torus.material.normalTexture.texture = vase.normal;
    scene.virtuals.push_back(std::move(torus));
    const RayScene objects(scene, SceneContent::VirtualOnly);
    Camera camera;
    camera.setFieldOfView(39.3);
    camera.worldFromCamera = lookAtPose({0.278f, 0.273f, -0.8f}, {0.278f, 0.273f, 0.0f});
    std::vector<RayHit> hits;
    std::vector<float> footprints;
    for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x)
            for (int s = 0; s < 4; ++s) {
                const glm::vec3 dir = glm::normalize(
                    camera.rayDirection(x + 0.25f + 0.5f * (s & 1), y + 0.25f + 0.5f * (s >> 1)));
                RayHit hit = objects.intersect(camera.position(), dir, 0.0f, INFINITY, true);
                if (!hit.hit()) continue;
                const float cosine = std::max(std::abs(glm::dot(hit.geometricNormal, dir)), 0.1f);
                footprints.push_back(hit.t / std::max(camera.fy, 1e-6f) / 2.0f / cosine);
                hits.push_back(hit);
            }
    std::vector<RayHit> looked = hits;
    for (auto _ : state) {
        for (size_t i = 0; i < hits.size(); ++i) {
            looked[i] = hits[i];
            lookUpMaterial(looked[i], footprints[i]);
        }
        benchmark::DoNotOptimize(looked.data());
    }
    state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(hits.size()));
    state.counters["lookups"] = static_cast<double>(hits.size());
}
BENCHMARK(BM_MaterialLookups)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);

// Cones from points on the floor around the ball, through the two visibility volumes and the delta volume
// (light cones) or the visibility volumes alone (shadow cones towards the light).
class ConeFixture : public benchmark::Fixture {
  public:
    void SetUp(const benchmark::State&) override {
        if (!volumes.empty()) return;
        const KernelScene k(128);
        scene = k.scene;
        region = k.region;
        VoxelGeometry sceneGeometry = voxelize(scene.real, region),
                      objectGeometry = voxelize(scene.virtuals, region);
        const RayScene realOnly(scene, SceneContent::RealOnly);
        const RayScene all(scene, SceneContent::VirtualOnly, &realOnly);
        const std::vector<ReflectiveShadowMap> full = {
            renderReflectiveShadowMap(all, scene.lights[0], region, 512)};
        const std::vector<ReflectiveShadowMap> alone = {
            renderReflectiveShadowMap(realOnly, scene.lights[0], region, 512)};
        const VoxelGeometry* both[] = {&sceneGeometry, &objectGeometry};
        const VoxelGeometry* sceneOnly[] = {&sceneGeometry};
        Grid3 fullLight = injectLight(full, region, both);
        PackedGrid3 delta = deltaVolume(fullLight, injectLight(alone, region, sceneOnly));
        volumes.push_back(buildMipChain(region, std::move(sceneGeometry.visibility)));
        volumes.push_back(buildMipChain(region, std::move(objectGeometry.visibility)));
        volumes.push_back(buildMipChain(region, std::move(delta)));
        // Floor points on a grid, cone directions over the hemisphere.
        const DiffuseConeSet set = makeDiffuseCones(9, 0.0f);
        for (int i = 0; i < 4096; ++i) {
            const glm::vec3 p(-0.9f + 1.8f * static_cast<float>(i % 64) / 63.0f, 0.0f,
                              -0.9f + 1.8f * static_cast<float>(i / 64) / 63.0f);
            Cone cone;
            cone.direction =
                glm::vec3(set.directions[i % 9].x, set.directions[i % 9].z, set.directions[i % 9].y);
            cone.origin = coneOrigin(p, {0, 1, 0}, cone.direction, region, settings);
            cone.tanHalfAngle = set.tanHalfAngle;
            cone.jitter = hashToUnit(static_cast<uint64_t>(i), 0);
            diffuse.push_back(cone);
            Cone shadow = cone;
            const glm::vec3 toLight = scene.lights[0].position - p;
            shadow.direction = glm::normalize(toLight);
            shadow.origin = coneOrigin(p, {0, 1, 0}, shadow.direction, region, settings);
            shadow.tanHalfAngle = std::tan(glm::radians(2.0f));
            shadow.maxDistance = glm::length(toLight);
            shadows.push_back(shadow);
        }
    }
    VisibilityVolumes visibility() const {
        return {&volumes[0], &volumes[1], VisibilityVolumes::Self::Scene};
    }

    Scene scene;
    VolumeRegion region;
    std::vector<MipVolume> volumes;  // scene visibility, object visibility, delta light
    std::vector<Cone> diffuse, shadows;
    ConeTraceSettings settings;
};

BENCHMARK_F(ConeFixture, DiffuseCones)(benchmark::State& state) {
    int64_t steps = 0;
    for (auto _ : state)
        for (const Cone& cone : diffuse)
            benchmark::DoNotOptimize(traceLightCone(cone, volumes[2], visibility(), settings, &steps));
    state.SetItemsProcessed(steps);  // cone samples
    state.counters["cones/s"] = benchmark::Counter(static_cast<double>(state.iterations() * diffuse.size()),
                                                   benchmark::Counter::kIsRate);
}

// The same cones over the pipeline's threads (TBB's default: every core), timed by the wall clock: the
// figure of issue 38's target, "on two threads" on the project's machine.
BENCHMARK_DEFINE_F(ConeFixture, DiffuseConesAllThreads)(benchmark::State& state) {
    std::vector<int64_t> steps(diffuse.size(), 0);
    int64_t total = 0;
    for (auto _ : state) {
        parallelFor(0, static_cast<int64_t>(diffuse.size()), 16, [&](int64_t i) {
            int64_t s = 0;
            benchmark::DoNotOptimize(traceLightCone(diffuse[i], volumes[2], visibility(), settings, &s));
            steps[i] = s;
        });
        for (int64_t s : steps) total += s;
    }
    state.SetItemsProcessed(total);
    state.counters["cones/s"] = benchmark::Counter(static_cast<double>(state.iterations() * diffuse.size()),
                                                   benchmark::Counter::kIsRate);
    state.SetLabel(std::to_string(tbb::this_task_arena::max_concurrency()) + " threads");
}
BENCHMARK_REGISTER_F(ConeFixture, DiffuseConesAllThreads)->UseRealTime();

// The same cones traced eight at a time in SIMD lanes (traceLightCones): what the pipeline's passes use.
BENCHMARK_F(ConeFixture, DiffuseConeLanes)(benchmark::State& state) {
    int64_t steps = 0;
    std::vector<glm::vec3> light(diffuse.size());
    for (auto _ : state) {
        traceLightCones(diffuse, volumes[2], visibility(), settings, light, &steps);
        benchmark::DoNotOptimize(light.data());
    }
    state.SetItemsProcessed(steps);
    state.counters["cones/s"] = benchmark::Counter(static_cast<double>(state.iterations() * diffuse.size()),
                                                   benchmark::Counter::kIsRate);
}

// The lanes over the pipeline's threads, 64 cones a task, timed by the wall clock.
BENCHMARK_DEFINE_F(ConeFixture, DiffuseConeLanesAllThreads)(benchmark::State& state) {
    constexpr int64_t kConesPerTask = 64;
    const int64_t tasks = (static_cast<int64_t>(diffuse.size()) + kConesPerTask - 1) / kConesPerTask;
    std::vector<int64_t> steps(static_cast<size_t>(tasks), 0);
    std::vector<glm::vec3> light(diffuse.size());
    int64_t total = 0;
    for (auto _ : state) {
        parallelFor(0, tasks, 1, [&](int64_t k) {
            const size_t begin = static_cast<size_t>(k * kConesPerTask);
            const size_t count = std::min<size_t>(kConesPerTask, diffuse.size() - begin);
            int64_t s = 0;
            traceLightCones(std::span(diffuse).subspan(begin, count), volumes[2], visibility(), settings,
                            std::span(light).subspan(begin, count), &s);
            steps[static_cast<size_t>(k)] = s;
        });
        benchmark::DoNotOptimize(light.data());
        for (int64_t s : steps) total += s;
    }
    state.SetItemsProcessed(total);
    state.counters["cones/s"] = benchmark::Counter(static_cast<double>(state.iterations() * diffuse.size()),
                                                   benchmark::Counter::kIsRate);
    state.SetLabel(std::to_string(tbb::this_task_arena::max_concurrency()) + " threads");
}
BENCHMARK_REGISTER_F(ConeFixture, DiffuseConeLanesAllThreads)->UseRealTime();

BENCHMARK_F(ConeFixture, ShadowCones)(benchmark::State& state) {
    int64_t steps = 0;
    for (auto _ : state)
        for (const Cone& cone : shadows)
            benchmark::DoNotOptimize(traceShadowCone(cone, visibility(), settings, &steps));
    state.SetItemsProcessed(steps);
    state.counters["cones/s"] = benchmark::Counter(static_cast<double>(state.iterations() * shadows.size()),
                                                   benchmark::Counter::kIsRate);
}

}  // namespace
}  // namespace deltagi

// As the command line and the Python module do: freed memory is kept for the next allocations (a kernel that
// allocates its result every call would otherwise time the host backing fresh pages).
int main(int argc, char** argv) {
    deltagi::retainFreedMemory();
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
