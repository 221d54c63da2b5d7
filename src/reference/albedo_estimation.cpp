#include "deltagi/albedo_estimation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <stdexcept>

#include <fmt/core.h>

#include "core/area_lights.h"
#include "core/environment_sampling.h"
#include "core/parallel.h"
#include "core/ray_scene.h"
#include "core/sampler.h"
#include "deltagi/error.h"
#include "reference/path_tracer.h"

namespace deltagi {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr int64_t kRowGrain = 1;  // one image row per task
// A vertex takes its own estimate when the pixels splatted onto it weigh at least this much together (in
// pixels' worth of barycentric weight); below it, the few pixels near its far corner say too little, and it
// takes the mesh's overall estimate.
constexpr double kMinVertexWeight = 0.1;
// Pixels whose neighbour's surface normal turns by more than this angle's cosine (about 18 degrees) sit on a
// crease (cameraHits).
constexpr float kCreaseCosine = 0.95f;
// Newton's step on the albedo (Estimator::update): the elasticity d log E / d log albedo that the first pass
// assumes, and the bounds of the measured one; albedos below kMinAlbedo are 0 (log 0 is not a number); a
// secant over a smaller step of log albedo is noise; kMaxRatio bounds the plain update before the logarithm.
constexpr float kStartElasticity = 1.0f;
constexpr float kMaxElasticity = 4.0f;
constexpr float kMinAlbedo = 1e-4f;
constexpr float kMinSecantStep = 1e-3f;
constexpr float kMaxRatio = 1e6f;
// Different streams for the irradiance paths and the specular paths of the same pixel and sample.
constexpr uint64_t kSpecularStream = 0x5bd1e995ull;

bool isFinite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void validate(const Scene& scene, const AlbedoOptions& options) {
    const std::string file = scene.file.empty() ? std::string("scene") : scene.file.string();
    if (!scene.background)
        throw InputError(
            file + ": background",
            "estimating the real scene's albedo needs its photo: the scene has no \"background\"");
    const Image& photo = *scene.background;
    if (photo.width() != scene.camera.width || photo.height() != scene.camera.height)
        throw InputError(file + ": background",
                         fmt::format("expected a photo of the camera's size {}x{}, got {}x{}",
                                     scene.camera.width, scene.camera.height, photo.width(), photo.height()));
    if (scene.real.empty())
        throw InputError(file + ": scene",
                         "estimating the real scene's albedo needs the real scene's meshes (\"scene\"), and "
                         "there are none");
    if (options.iterations < 1)
        throw InputError("iterations", fmt::format("expected at least 1 pass, got {}", options.iterations));
    if (!options.meshes.empty() && options.meshes.size() != scene.real.size())
        throw std::invalid_argument("estimateAlbedo: options.meshes must have one flag per real mesh");
    if (options.samplesPerPixel < 1)
        throw InputError("samples per pixel", fmt::format("expected at least 1 sample per pixel, got {}",
                                                          options.samplesPerPixel));
}

// What a camera ray through a pixel's centre finds.
struct PixelHit {
    RayHit hit;
    glm::vec3 direction{0.0f};
    int mesh = -1;     // index into Scene::real; -1: nothing, or an emitter
    bool use = false;  // counted in the sums (not at a silhouette, unless its mesh has no other pixel)
};

std::vector<PixelHit> cameraHits(const Scene& real, const RayScene& rays, const Camera& camera,
                                 bool skipEdges) {
    const int w = camera.width, h = camera.height;
    std::vector<PixelHit> pixels(static_cast<size_t>(w) * h);
    const glm::vec3 eye = camera.position();
    parallelFor(0, h, kRowGrain, [&](int64_t y) {
        for (int x = 0; x < w; ++x) {
            PixelHit& p = pixels[static_cast<size_t>(y) * w + x];
            p.direction = glm::normalize(camera.rayDirection(x + 0.5f, static_cast<float>(y) + 0.5f));
            p.hit = rays.intersect(eye, p.direction);
            if (p.hit.hit() && !p.hit.material->emits() && p.hit.mesh)
                p.mesh = static_cast<int>(p.hit.mesh - real.real.data());
        }
    });
    // A pixel at a silhouette or a crease: a 4-neighbour inside the image sees another mesh, or another face
    // of it (a box's top seen beside its side: the photo's pixel mixes both, its centre sees one).
    auto interior = [&](int x, int y) {
        const PixelHit& p = pixels[static_cast<size_t>(y) * w + x];
        const std::array<glm::ivec2, 4> steps{{{1, 0}, {-1, 0}, {0, 1}, {0, -1}}};
        for (glm::ivec2 s : steps) {
            const int nx = x + s.x, ny = y + s.y;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            const PixelHit& n = pixels[static_cast<size_t>(ny) * w + nx];
            if (n.mesh != p.mesh || glm::dot(n.hit.normal, p.hit.normal) < kCreaseCosine) return false;
        }
        return true;
    };
    std::vector<size_t> interiorCount(real.real.size(), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            PixelHit& p = pixels[static_cast<size_t>(y) * w + x];
            if (p.mesh < 0) continue;
            p.use = !skipEdges || interior(x, y);
            if (p.use) ++interiorCount[p.mesh];
        }
    for (PixelHit& p : pixels)  // a mesh seen only at silhouettes: all of its pixels
        if (p.mesh >= 0 && interiorCount[p.mesh] == 0) p.use = true;
    return pixels;
}

// The sums of one pass, per mesh and (per vertex) per vertex.
struct MeshSums {
    glm::dvec3 reflected{0.0}, irradiance{0.0};  // sum of pi (L - L_specular), sum of E
    size_t used = 0, clamped = 0;
    std::vector<glm::dvec3> vertexReflected, vertexIrradiance;
    std::vector<double> vertexWeight;
};

// The largest albedo the material allows: 1, less the specular reflectance of a Phong material (energy
// conservation, which the scene reader checks).
glm::vec3 largestAlbedo(const Material& material) {
    if (material.model != MaterialModel::Phong) return glm::vec3(1.0f);
    return glm::clamp(glm::vec3(1.0f) - material.specular, glm::vec3(0.0f), glm::vec3(1.0f));
}

// Per channel: the ratio, clamped to [0, largest] (and whether it was above); `fallback` where nothing lit
// it.
glm::vec3 clampedRatio(glm::dvec3 reflected, glm::dvec3 irradiance, glm::vec3 largest, glm::vec3 fallback,
                       bool& above) {
    glm::vec3 result = fallback;
    for (int c = 0; c < 3; ++c) {
        if (!(irradiance[c] > 0.0)) continue;
        const double ratio = reflected[c] / irradiance[c];
        above = above || ratio > largest[c];
        result[c] = static_cast<float>(std::clamp(ratio, 0.0, static_cast<double>(largest[c])));
    }
    return result;
}

// The working scene's materials for the next pass: `estimate` as applyAlbedo() puts it.
void applyTo(std::vector<TriangleMesh>& meshes, const AlbedoEstimate& estimate) {
    for (size_t m = 0; m < meshes.size(); ++m) {
        TriangleMesh& mesh = meshes[m];
        const MeshAlbedo& a = estimate.meshes[m];
        if (!a.estimated) continue;
        mesh.material.albedo = a.albedo;
        mesh.material.baseColorTexture = {};
        if (estimate.granularity == AlbedoGranularity::PerMesh || a.vertexAlbedo.empty()) {
            mesh.colors.clear();  // they would multiply the estimate
            continue;
        }
        mesh.colors.resize(mesh.positions.size());
        for (size_t v = 0; v < mesh.positions.size(); ++v)
            for (int c = 0; c < 3; ++c)
                mesh.colors[v][c] = a.albedo[c] > 0.0f ? a.vertexAlbedo[v][c] / a.albedo[c] : 0.0f;
    }
}

std::string channelList(glm::dvec3 reflected, glm::dvec3 irradiance) {
    constexpr const char* kChannel[] = {"r", "g", "b"};
    std::string list;
    for (int c = 0; c < 3; ++c) {
        if (!(irradiance[c] > 0.0 && reflected[c] > irradiance[c])) continue;
        if (!list.empty()) list += ',';
        list += kChannel[c];
    }
    return list;
}

class Estimator {
  public:
    Estimator(const Scene& scene, const AlbedoOptions& options)
        : scene_(scene),
          options_(options),
          work_(realOnly(scene)),
          rays_(work_, SceneContent::RealOnly),
          emitters_(work_, SceneContent::RealOnly) {
        if (scene.environment) environment_.emplace(*scene.environment);
        PathSettings settings;
        settings.rouletteStartBounce = options.rouletteStartBounce;
        settings.rayOffset =
            kRayOffsetScale * std::max(rays_.bounds().empty() ? 1.0f : rays_.bounds().maxExtent(), 1e-3f);
        tracer_.emplace(rays_, emitters_, scene.lights, settings, environment_ ? &*environment_ : nullptr);
        pixels_ = cameraHits(work_, rays_, scene.camera, options.skipEdgePixels);
        for (const TriangleMesh& mesh : work_.real) largest_.push_back(largestAlbedo(mesh.material));
        newton_.resize(work_.real.size());
        white_.albedo = glm::vec3(1.0f);
        white_.specular = glm::vec3(0.0f);
    }

    AlbedoEstimate run() {
        AlbedoEstimate estimate;
        estimate.granularity = options_.granularity;
        for (const TriangleMesh& mesh : work_.real) {
            MeshAlbedo a;
            a.name = mesh.name;
            a.albedo = mesh.material.albedo;
            a.estimated = options_.meshes.empty() || options_.meshes[estimate.meshes.size()];
            estimate.meshes.push_back(std::move(a));
        }
        for (int pass = 0; pass < options_.iterations; ++pass) {
            tracePass();
            const std::vector<MeshSums> sums = accumulate();
            estimate.changePerIteration.push_back(update(estimate, sums));
            applyTo(work_.real, estimate);
            rays_.updateMaterials();
        }
        addWarnings(estimate);
        return estimate;
    }

  private:
    static Scene realOnly(const Scene& scene) {
        Scene work;
        work.real = scene.real;
        for (TriangleMesh& mesh : work.real) mesh.material.baseColorTexture = {};
        return work;
    }

    // E and the specular share of L at every used pixel, path traced with the working scene's materials.
    void tracePass() {
        const int w = scene_.camera.width, h = scene_.camera.height;
        irradiance_.assign(pixels_.size(), glm::vec3(0.0f));
        specular_.assign(pixels_.size(), glm::vec3(0.0f));
        // The materials with their diffuse part taken away: what the photo shows besides the diffuse part.
        std::vector<Material> glossOnly;
        for (const TriangleMesh& mesh : work_.real) {
            glossOnly.push_back(mesh.material);
            glossOnly.back().albedo = glm::vec3(0.0f);
        }
        const double n = options_.samplesPerPixel;
        parallelFor(0, h, kRowGrain, [&](int64_t y) {
            for (int x = 0; x < w; ++x) {
                const size_t i = static_cast<size_t>(y) * w + x;
                const PixelHit& p = pixels_[i];
                if (!p.use) continue;
                const Material& material = work_.real[p.mesh].material;
                const bool glossy = material.specular != glm::vec3(0.0f) ||
                                    material.model == MaterialModel::MetallicRoughness;
                RayHit white = p.hit, gloss = p.hit;
                white.material = &white_;
                white.surface = constantSurfaceMaterial(white_);
                gloss.material = &glossOnly[p.mesh];
                gloss.surface.diffuse =
                    glm::vec3(0.0f);  // the hit's textured material, less its diffuse part
                glm::dvec3 e(0.0), s(0.0);
                for (int sample = 0; sample < options_.samplesPerPixel; ++sample) {
                    // The same numbers every pass: the change from pass to pass is the albedos', not noise.
                    Sampler sampler(i, static_cast<uint64_t>(sample), options_.seed);
                    const glm::vec3 reflected = tracer_->radianceFromHit(white, p.direction, sampler);
                    if (isFinite(reflected)) e += glm::dvec3(reflected);
                    if (!glossy) continue;
                    Sampler glossSampler(i, static_cast<uint64_t>(sample), options_.seed ^ kSpecularStream);
                    const glm::vec3 shine = tracer_->radianceFromHit(gloss, p.direction, glossSampler);
                    if (isFinite(shine)) s += glm::dvec3(shine);
                }
                // A white Lambertian surface reflects E / pi in every direction.
                irradiance_[i] = glm::vec3(e * (static_cast<double>(kPi) / n));
                specular_[i] = glm::vec3(s / n);
            }
        });
    }

    // The pass's sums, in pixel order (the same with any thread count).
    std::vector<MeshSums> accumulate() const {
        const bool perVertex = options_.granularity == AlbedoGranularity::PerVertex;
        std::vector<MeshSums> sums(work_.real.size());
        if (perVertex)
            for (size_t m = 0; m < sums.size(); ++m) {
                const size_t count = work_.real[m].positions.size();
                sums[m].vertexReflected.assign(count, glm::dvec3(0.0));
                sums[m].vertexIrradiance.assign(count, glm::dvec3(0.0));
                sums[m].vertexWeight.assign(count, 0.0);
            }
        const int w = scene_.camera.width;
        for (size_t i = 0; i < pixels_.size(); ++i) {
            const PixelHit& p = pixels_[i];
            const glm::vec3 e = irradiance_[i];
            if (!p.use || !(e.x + e.y + e.z > 0.0f)) continue;  // unlit: says nothing of the albedo
            const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
            const glm::vec3 photo = glm::max(scene_.background->rgb(x, y), glm::vec3(0.0f));
            const glm::vec3 reflected = kPi * glm::max(photo - specular_[i], glm::vec3(0.0f));
            if (!isFinite(reflected)) continue;
            MeshSums& s = sums[p.mesh];
            s.reflected += glm::dvec3(reflected);
            s.irradiance += glm::dvec3(e);
            ++s.used;
            if (glm::any(glm::greaterThan(reflected, e * largest_[p.mesh]))) ++s.clamped;
            if (!perVertex) continue;
            const glm::uvec3 tri = work_.real[p.mesh].triangles[p.hit.triangle];
            const glm::vec3 weights(1.0f - p.hit.barycentric.x - p.hit.barycentric.y, p.hit.barycentric.x,
                                    p.hit.barycentric.y);
            for (int k = 0; k < 3; ++k) {
                const double b = std::clamp(weights[k], 0.0f, 1.0f);
                s.vertexReflected[tri[k]] += b * glm::dvec3(reflected);
                s.vertexIrradiance[tri[k]] += b * glm::dvec3(e);
                s.vertexWeight[tri[k]] += b;
            }
        }
        return sums;
    }

    // The new estimate from a pass's sums; returns the largest change of a mesh's overall albedo.
    //
    // The plain update, albedo = pi L / E(previous albedo), oscillates and can diverge: E grows with the
    // albedo (a surface lit only by the others, the Cornell box's ceiling, has E about proportional to it),
    // so a too-dark guess gives a too-bright next one and so on. Per channel, it solves
    // log a + log E(a) = log(pi L) by Newton's method instead, with the elasticity f = d log E / d log a
    // measured by the secant between the last two passes (same random numbers: the difference is the
    // albedos', not noise): log a' = log a + (log(pi L / E) - log a) / (1 + f). f = 0 is the plain update;
    // the first pass takes f = 1 (the geometric mean of the guess and the plain update).
    float update(AlbedoEstimate& estimate, const std::vector<MeshSums>& sums) {
        float change = 0.0f;
        for (size_t m = 0; m < sums.size(); ++m) {
            MeshAlbedo& a = estimate.meshes[m];
            const MeshSums& s = sums[m];
            a.pixelsUsed = s.used;
            a.pixelsClamped = s.clamped;
            a.reflectedSum = s.reflected;
            a.irradianceSum = s.irradiance;
            a.clamped = false;
            if (!options_.meshes.empty() && !options_.meshes[m]) continue;  // given, not estimated
            const glm::vec3 previous = a.albedo;
            const glm::vec3 largest = largest_[m];
            NewtonState& state = newton_[m];
            if (s.used > 0) {
                const glm::vec3 ratio =
                    clampedRatio(s.reflected, s.irradiance, glm::vec3(kMaxRatio), previous, a.clamped);
                a.clamped = glm::any(glm::greaterThan(ratio, largest));
                for (int c = 0; c < 3; ++c) {
                    if (!(s.irradiance[c] > 0.0)) continue;
                    const float x = std::log(std::max(previous[c], kMinAlbedo));
                    const float target = std::log(std::max(ratio[c], kMinAlbedo));
                    if (state.known && std::abs(x - state.logAlbedo[c]) > kMinSecantStep)
                        state.elasticity[c] = std::clamp(
                            -(target - state.logRatio[c]) / (x - state.logAlbedo[c]), 0.0f, kMaxElasticity);
                    state.logAlbedo[c] = x;
                    state.logRatio[c] = target;
                    const float next = std::exp(x + (target - x) / (1.0f + state.elasticity[c]));
                    a.albedo[c] = ratio[c] > kMinAlbedo ? std::clamp(next, 0.0f, largest[c]) : 0.0f;
                }
                state.known = true;
            }
            const glm::vec3 difference = glm::abs(a.albedo - previous);
            change = std::max({change, difference.x, difference.y, difference.z});
            if (s.vertexWeight.empty()) continue;
            updateVertices(a, s, previous, state.elasticity, largest);
        }
        return change;
    }

    // The same step for each vertex, with its mesh's elasticity (a vertex's own pixels are too few to measure
    // one).
    static void updateVertices(MeshAlbedo& a, const MeshSums& s, glm::vec3 meshPrevious, glm::vec3 elasticity,
                               glm::vec3 largest) {
        std::vector<glm::vec3> previous = std::move(a.vertexAlbedo);
        if (previous.size() != s.vertexWeight.size()) previous.assign(s.vertexWeight.size(), meshPrevious);
        a.vertexAlbedo.assign(s.vertexWeight.size(), a.albedo);
        a.verticesSeen = a.verticesClamped = 0;
        for (size_t v = 0; v < s.vertexWeight.size(); ++v) {
            if (s.vertexWeight[v] < kMinVertexWeight) continue;
            bool above = false;
            const glm::vec3 ratio = clampedRatio(s.vertexReflected[v], s.vertexIrradiance[v],
                                                 glm::vec3(kMaxRatio), previous[v], above);
            glm::vec3 next = a.albedo;
            for (int c = 0; c < 3; ++c) {
                const float x = std::log(std::max(previous[v][c], kMinAlbedo));
                const float target = std::log(std::max(ratio[c], kMinAlbedo));
                next[c] =
                    ratio[c] > kMinAlbedo
                        ? std::clamp(std::exp(x + (target - x) / (1.0f + elasticity[c])), 0.0f, largest[c])
                        : 0.0f;
            }
            a.vertexAlbedo[v] = next;
            ++a.verticesSeen;
            if (glm::any(glm::greaterThan(ratio, largest))) ++a.verticesClamped;
        }
    }

    void addWarnings(AlbedoEstimate& estimate) const {
        for (size_t m = 0; m < estimate.meshes.size(); ++m) {
            const MeshAlbedo& a = estimate.meshes[m];
            if (!a.estimated || work_.real[m].material.emits()) continue;  // given, or a lamp
            if (a.pixelsUsed == 0) {
                estimate.warnings.push_back(
                    fmt::format("real mesh '{}': no lit pixel of the photo shows it; its albedo stays as "
                                "given ({}, {}, {})",
                                a.name, a.albedo.x, a.albedo.y, a.albedo.z));
                continue;
            }
            if (a.clamped)
                estimate.warnings.push_back(fmt::format(
                    "real mesh '{}': the photo is brighter than any albedo explains (channel {}; {} of its "
                    "{} "
                    "pixels brighter); its albedo is clamped to ({}, {}, {})",
                    a.name, channelList(a.reflectedSum, a.irradianceSum * glm::dvec3(largest_[m])),
                    a.pixelsClamped, a.pixelsUsed, a.albedo.x, a.albedo.y, a.albedo.z));
            if (a.verticesClamped > 0)
                estimate.warnings.push_back(fmt::format(
                    "real mesh '{}': the photo is brighter than any albedo explains at {} of its {} vertices "
                    "seen ({} of {} pixels brighter); their albedo is clamped to the largest possible",
                    a.name, a.verticesClamped, a.verticesSeen, a.pixelsClamped, a.pixelsUsed));
        }
    }

    const Scene& scene_;
    const AlbedoOptions& options_;
    Scene work_;  // the real meshes, with the current estimates as their materials
    RayScene rays_;
    AreaLights emitters_;
    std::optional<EnvironmentSampler> environment_;
    std::optional<PathTracer> tracer_;
    Material white_;
    std::vector<PixelHit> pixels_;
    std::vector<glm::vec3> largest_;  // per mesh: largestAlbedo()
    struct NewtonState {
        glm::vec3 elasticity{kStartElasticity};
        glm::vec3 logAlbedo{0.0f}, logRatio{0.0f};  // the last pass's
        bool known = false;
    };
    std::vector<NewtonState> newton_;               // per mesh
    std::vector<glm::vec3> irradiance_, specular_;  // per pixel, this pass
};

}  // namespace

AlbedoEstimate estimateAlbedo(const Scene& scene, const AlbedoOptions& options) {
    validate(scene, options);
    return Estimator(scene, options).run();
}

void applyAlbedo(Scene& scene, const AlbedoEstimate& estimate) {
    if (estimate.meshes.size() != scene.real.size())
        throw std::invalid_argument("applyAlbedo: the estimate is for another scene (mesh count)");
    applyTo(scene.real, estimate);
}

}  // namespace deltagi
