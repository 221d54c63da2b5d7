// Microbenchmarks of the pipeline's hot kernels (Google Benchmark): voxelization, light injection, mipmaps
// and the cone marcher. Items per second are triangles, RSM texels, voxels and cone samples (steps). Run:
//   build/bench/deltagi_microbench [--benchmark_filter=Cone] [--benchmark_repetitions=5]
// The whole-frame figures come from `deltagi bench` (docs in README "Performance").
#include <benchmark/benchmark.h>

#include <cmath>

#include "cone_trace.h"
#include "inject.h"
#include "mipmap.h"
#include "ray_scene.h"
#include "reflective_shadow_map.h"
#include "shapes.h"
#include "voxelize.h"

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
        Grid3 delta = deltaVolume(fullLight, injectLight(alone, region, sceneOnly));
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

BENCHMARK_MAIN();
