#include "reference/path_tracer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "core/brdf.h"
#include "core/brdf_sampling.h"
#include "core/parallel.h"
#include "deltagi/reference.h"
#include "pipeline/composite.h"
#include "pipeline/gbuffer.h"

namespace deltagi {

namespace {

// A pass (one sample per pixel) is split into rows, one row per task.
constexpr int64_t kRowGrain = 1;
// Russian roulette never continues with more than this probability, so that paths in a white room end.
constexpr float kMaxSurvivalProbability = 0.95f;

// Multiple importance sampling (Veach 1997): the power heuristic's weight of a sample drawn with pdf `a`
// when the other strategy would have drawn it with pdf `b`.
float powerHeuristic(float a, float b) {
    const float a2 = a * a, b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

float maxComponent(glm::vec3 v) {
    return std::max(v.x, std::max(v.y, v.z));
}
bool isFinite(glm::vec3 v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

namespace {

// The disk a sphere light shows a point p: centred on the light, facing p, of the light's radius; a point q
// on it brings I / |q - p|^2 when drawn uniformly (sampleLightPoint).
struct LightDisk {
    glm::vec3 normal{0.0f};  // unit, from the light towards p
    float distance = 0.0f;   // from p to the centre
    float area = 0.0f;
};

// Whether `light` is a sphere seen from p (a point or spot light with a radius, p outside its centre).
std::optional<LightDisk> lightDisk(const Light& light, glm::vec3 p) {
    if (light.type == Light::Type::Directional || !(light.radius > 0.0f) || light.fromEnvironment)
        return std::nullopt;
    const glm::vec3 axis = p - light.position;
    const float d = glm::length(axis);
    if (!(d > 0.0f)) return std::nullopt;
    return LightDisk{axis / d, d, std::numbers::pi_v<float> * light.radius * light.radius};
}

// The density per unit solid angle with which a uniform point of the disk lies in direction wi from p,
// `distance` away: distance^2 / (area cos), the disk's cosine taken towards wi.
float diskPdf(const LightDisk& disk, glm::vec3 wi, float distance) {
    const float cosine = std::abs(glm::dot(wi, disk.normal));
    return cosine > 0.0f ? distance * distance / (disk.area * cosine) : 0.0f;
}

}  // namespace

LightSample sampleLightPoint(const Light& light, glm::vec3 p, float u1, float u2) {
    if (light.type == Light::Type::Directional || !(light.radius > 0.0f)) return sampleLight(light, p);
    const glm::vec3 axis = p - light.position;
    const float d = glm::length(axis);
    if (!(d > 0.0f)) return sampleLight(light, p);
    const glm::mat3 frame = frameAround(axis / d);
    const float r = light.radius * std::sqrt(u1);
    const float phi = 2.0f * std::numbers::pi_v<float> * u2;
    const glm::vec3 onDisk = light.position + frame * glm::vec3(r * std::cos(phi), r * std::sin(phi), 0.0f);
    const glm::vec3 toLight = onDisk - p;
    LightSample s;
    const float d2 = glm::dot(toLight, toLight);
    if (!(d2 > 0.0f)) return s;
    s.distance = std::sqrt(d2);
    s.wi = toLight / s.distance;
    // The spot's cone is the lamp's: its falloff is taken along the axis from the centre.
    s.irradiance = light.power() * (spotFalloff(light, axis / d) / d2);
    return s;
}

glm::vec3 PathTracer::lightsAlong(glm::vec3 position, const BrdfSample& s, const RayHit& next) const {
    glm::vec3 sum(0.0f);
    for (const Light& light : lights_) {
        const std::optional<LightDisk> disk = lightDisk(light, position);
        if (!disk) continue;
        // Where the ray meets the disk's plane, and whether within its radius and short of the next surface.
        const float towards = -glm::dot(s.wi, disk->normal);
        if (!(towards > 0.0f)) continue;
        const float t = disk->distance / towards;
        const glm::vec3 offCentre = position + t * s.wi - light.position;
        if (glm::dot(offCentre, offCentre) > light.radius * light.radius) continue;
        if (next.hit() && next.t < t - 2.0f * settings_.rayOffset) continue;
        const float pdfLight = diskPdf(*disk, s.wi, t);
        if (!(pdfLight > 0.0f) || !std::isfinite(pdfLight)) continue;
        // The disk's radiance, I / (area cos): what sampleLightPoint's point there brings (I / t^2) per unit
        // of the density it was drawn with.
        const glm::vec3 irradiance = light.power() * (spotFalloff(light, disk->normal) / (t * t));
        sum += irradiance * (pdfLight * powerHeuristic(s.pdf, pdfLight));
    }
    return sum;
}

glm::vec3 PathTracer::offsetOrigin(const RayHit& hit, glm::vec3 towards) const {
    const float side = glm::dot(towards, hit.normal) >= 0.0f ? 1.0f : -1.0f;
    return hit.position + (side * settings_.rayOffset) * hit.normal;
}

template <typename Add>
void PathTracer::sampleLights(const RayHit& hit, glm::vec3 wo, Sampler& sampler, Add&& add) const {
    for (const Light& light : lights_) {
        const glm::vec2 u = sampler.uniform2();
        if (light.fromEnvironment) continue;  // its light is in the map, sampled below
        const LightSample s = sampleLightPoint(light, hit.position, u.x, u.y);
        const float cosTheta = glm::dot(s.wi, hit.normal);
        if (cosTheta <= 0.0f || s.irradiance == glm::vec3(0.0f)) continue;
        const glm::vec3 origin = offsetOrigin(hit, s.wi);
        const float tMax = std::isfinite(s.distance) ? s.distance - 2.0f * settings_.rayOffset : s.distance;
        if (tMax <= 0.0f) continue;
        // A sphere light's point is weighted against the BRDF sample that could meet it (lightsAlong()).
        float weight = 1.0f;
        if (const std::optional<LightDisk> disk = lightDisk(light, hit.position))
            weight =
                powerHeuristic(diskPdf(*disk, s.wi, s.distance), brdfPdf(hit.surface, hit.normal, wo, s.wi));
        add(origin, s.wi, tMax,
            evalBrdf(hit.surface, hit.normal, wo, s.wi) * s.irradiance * (cosTheta * weight));
    }
    if (!environment_) return;
    const glm::vec2 u = sampler.uniform2();
    const EnvironmentSampler::Sample s = environment_->sample(u.x, u.y);
    const float cosTheta = glm::dot(s.wi, hit.normal);
    if (!(s.pdf > 0.0f) || cosTheta <= 0.0f || s.radiance == glm::vec3(0.0f)) return;
    const float weight = powerHeuristic(s.pdf, brdfPdf(hit.surface, hit.normal, wo, s.wi));
    add(offsetOrigin(hit, s.wi), s.wi, std::numeric_limits<float>::infinity(),
        evalBrdf(hit.surface, hit.normal, wo, s.wi) * s.radiance * (cosTheta * weight / s.pdf));
}

glm::vec3 PathTracer::directLight(const RayHit& hit, glm::vec3 wo, Sampler& sampler) const {
    glm::vec3 sum(0.0f);
    sampleLights(hit, wo, sampler, [&](glm::vec3 origin, glm::vec3 direction, float tMax, glm::vec3 light) {
        if (!rays_.occluded(origin, direction, 0.0f, tMax)) sum += light;
    });
    return sum;
}

template <typename Add>
void PathTracer::sampleEmitters(const RayHit& hit, glm::vec3 wo, float uTriangle, float u1, float u2,
                                Add&& add) const {
    const SurfaceMaterial& m = hit.surface;
    if (areaLights_.empty() || (m.diffuse == glm::vec3(0.0f) && m.specular == glm::vec3(0.0f))) return;
    const AreaLightSample s = areaLights_.sample(uTriangle, u1, u2);
    const glm::vec3 toLight = s.position - hit.position;
    const float d2 = glm::dot(toLight, toLight);
    if (!(d2 > 0.0f)) return;
    const float d = std::sqrt(d2);
    const glm::vec3 wi = toLight / d;
    const float cosSurface = glm::dot(wi, hit.normal);
    const float cosLight = std::abs(glm::dot(wi, s.normal));
    if (cosSurface <= 0.0f || !(cosLight > 0.0f)) return;
    // The shadow ray aims at the point from the offset origin: a ray parallel to wi would meet the emitter's
    // plane short of the point at grazing angles, and the emitter would shadow itself.
    const glm::vec3 origin = offsetOrigin(hit, wi);
    const glm::vec3 toPoint = s.position - origin;
    const float distance = glm::length(toPoint);
    const float tMax = distance - 2.0f * settings_.rayOffset;
    if (tMax <= 0.0f) return;
    const float pdfLight = s.pdfArea * d2 / cosLight;  // per unit solid angle at the hit
    if (!(pdfLight > 0.0f) || !std::isfinite(pdfLight)) return;
    const float weight = powerHeuristic(pdfLight, brdfPdf(m, hit.normal, wo, wi));
    add(origin, toPoint / distance, tMax,
        evalBrdf(m, hit.normal, wo, wi) * s.radiance * (cosSurface * weight / pdfLight));
}

glm::vec3 PathTracer::emittedLight(const RayHit& hit, glm::vec3 wo, Sampler& sampler) const {
    const float uTriangle = sampler.uniform();
    const glm::vec2 u = sampler.uniform2();
    glm::vec3 light(0.0f);
    sampleEmitters(hit, wo, uTriangle, u.x, u.y,
                   [&](glm::vec3 origin, glm::vec3 direction, float tMax, glm::vec3 l) {
                       if (!rays_.occluded(origin, direction, 0.0f, tMax)) light = l;
                   });
    return light;
}

float PathTracer::emitterWeight(const RayHit& at, glm::vec3 direction, glm::vec3 previousPosition,
                                float previousPdf) const {
    const glm::vec3 step = at.position - previousPosition;
    const float cosLight = std::abs(glm::dot(at.geometricNormal, direction));
    const float pdfLight = cosLight > 0.0f ? areaLights_.pdfArea(triangleEmission(*at.mesh, at.triangle)) *
                                                 glm::dot(step, step) / cosLight
                                           : std::numeric_limits<float>::infinity();
    return powerHeuristic(previousPdf, pdfLight);
}

glm::vec3 PathTracer::lastBounceLight(const RayHit& hit, const BrdfSample& s, const RayHit& next) const {
    glm::vec3 light = lightsAlong(hit.position, s, next);
    if (!next.hit() && environment_)
        light += environment_->radiance(s.wi) * powerHeuristic(s.pdf, environment_->pdf(s.wi));
    if (next.hit() && next.surface.emits())
        light += next.surface.emission * emitterWeight(next, s.wi, hit.position, s.pdf);
    return s.weight * light;
}

bool PathTracer::scatter(PathState& p, const BrdfSample& s, float uRoulette) const {
    p.throughput *= s.weight;
    if (p.bounce + 1 >= settings_.rouletteStartBounce) {
        const float survive = std::min(maxComponent(p.throughput), kMaxSurvivalProbability);
        if (!(uRoulette < survive)) return false;
        p.throughput /= survive;
    }
    p.direction = s.wi;
    p.previousPosition = p.hit.position;
    p.previousPdf = s.pdf;
    return true;
}

glm::vec3 PathTracer::radiance(glm::vec3 origin, glm::vec3 direction, Sampler& sampler) const {
    return radianceFromHit(rays_.intersect(origin, direction), direction, sampler);
}

glm::vec3 PathTracer::radianceFromHit(const RayHit& firstHit, glm::vec3 direction, Sampler& sampler) const {
    if (!firstHit.hit()) return environment_ ? environment_->radiance(direction) : glm::vec3(0.0f);
    PathState path;
    path.hit = firstHit;
    path.direction = direction;
    trace(path, sampler);
    return path.radiance;
}

void PathTracer::trace(PathState& p, Sampler& sampler) const {
    for (; p.hit.hit(); ++p.bounce) {
        const RayHit& hit = p.hit;
        const glm::vec3 wo = -p.direction;
        // Seen by the camera: all of it.
        if (hit.surface.emits())
            p.radiance +=
                p.throughput * hit.surface.emission *
                (p.bounce > 0 ? emitterWeight(hit, p.direction, p.previousPosition, p.previousPdf) : 1.0f);
        // The emitters' numbers first, then the lights' (the order of the references rendered before).
        const glm::vec3 emitted = emittedLight(hit, wo, sampler);
        p.radiance += p.throughput * (directLight(hit, wo, sampler) + emitted);
        const bool lastBounce = p.bounce + 1 >= settings_.maxBounces;
        // Always the same three requests per bounce, whatever happens, to keep the two correlated paths in
        // step.
        const float uLobe = sampler.uniform();
        const glm::vec2 u = sampler.uniform2();
        const float uRoulette = sampler.uniform();
        const BrdfSample s = sampleBrdf(hit.surface, hit.normal, wo, uLobe, u.x, u.y);
        if (!s.valid()) break;
        if (lastBounce) {
            // The bounce limit (a direct-light-only reference: maxBounces 1): the BRDF sample still brings
            // its MIS share of the direct light, the environment or an emitter it meets, and nothing beyond.
            // Without it the light sample's share alone fell short of the map's direct light.
            p.radiance +=
                p.throughput * lastBounceLight(hit, s, rays_.intersect(offsetOrigin(hit, s.wi), s.wi));
            break;
        }
        const glm::vec3 from = offsetOrigin(hit, s.wi);
        const glm::vec3 position = hit.position;  // p.hit is replaced below
        if (!scatter(p, s, uRoulette)) break;
        p.hit = rays_.intersect(from, p.direction);
        p.radiance += p.throughput * lightsAlong(position, s, p.hit);
        // A path that leaves the scene sees the environment, weighted against the light sample of
        // directLight().
        if (!p.hit.hit() && environment_)
            p.radiance += p.throughput * environment_->radiance(p.direction) *
                          powerHeuristic(s.pdf, environment_->pdf(p.direction));
    }
}

DifferentialPathTracer::DifferentialPathTracer(const PathTracer& with, const PathTracer& without,
                                               const RayScene& objects)
    : with_(with),
      without_(without),
      objects_(objects),
      sameEmitters_(with.areaLights_.size() == without.areaLights_.size()) {}

DifferentialPathTracer::Radiance DifferentialPathTracer::radiance(glm::vec3 origin, glm::vec3 direction,
                                                                  const RayHit& firstHit,
                                                                  Sampler& sampler) const {
    Radiance r;
    if (!firstHit.hit()) {  // the same environment (or nothing) in both
        r.with = r.without = with_.radianceFromHit(firstHit, direction, sampler);
        return r;
    }
    if (firstHit.isVirtual) {  // apart from the start
        Sampler samplerWithout = sampler;
        r.with = with_.radianceFromHit(firstHit, direction, sampler);
        r.without = without_.radiance(origin, direction, samplerWithout);
        return r;
    }
    const RayScene& real = without_.rays_;
    const PathTracer& shared = with_;  // the settings, lights and environment are the same in both
    // Shadow rays: blocked in the real scene (and so in both), or by an object (in `with` alone).
    glm::vec3 directWith(0.0f), directWithout(0.0f), emittedWith(0.0f), emittedWithout(0.0f);
    auto intoBoth = [&real, this](glm::vec3& with, glm::vec3& without) {
        return [&real, this, w = &with, wo = &without](glm::vec3 from, glm::vec3 towards, float tMax,
                                                       glm::vec3 light) {
            if (real.occluded(from, towards, 0.0f, tMax)) return;
            *wo += light;
            if (!objects_.occluded(from, towards, 0.0f, tMax)) *w += light;
        };
    };
    PathState p;  // the shared path; its radiance is `with`'s, `without` gathers apart
    p.hit = firstHit;
    p.direction = direction;
    glm::vec3 without(0.0f);
    for (; p.hit.hit(); ++p.bounce) {
        const RayHit& hit = p.hit;
        const glm::vec3 wo = -p.direction;
        if (hit.surface.emits()) {
            p.radiance +=
                p.throughput * hit.surface.emission *
                (p.bounce > 0 ? with_.emitterWeight(hit, p.direction, p.previousPosition, p.previousPdf)
                              : 1.0f);
            without +=
                p.throughput * hit.surface.emission *
                (p.bounce > 0 ? without_.emitterWeight(hit, p.direction, p.previousPosition, p.previousPdf)
                              : 1.0f);
        }
        directWith = directWithout = emittedWith = emittedWithout = glm::vec3(0.0f);
        const float uTriangle = sampler.uniform();
        const glm::vec2 uEmitter = sampler.uniform2();
        const float uEmitter1 = uEmitter.x, uEmitter2 = uEmitter.y;
        if (sameEmitters_) {
            shared.sampleEmitters(hit, wo, uTriangle, uEmitter1, uEmitter2,
                                  intoBoth(emittedWith, emittedWithout));
        } else {  // an object emits: each samples its own emitters, with the same numbers
            glm::vec3 unused(0.0f);
            with_.sampleEmitters(hit, wo, uTriangle, uEmitter1, uEmitter2, intoBoth(emittedWith, unused));
            without_.sampleEmitters(hit, wo, uTriangle, uEmitter1, uEmitter2,
                                    [&](glm::vec3 from, glm::vec3 towards, float tMax, glm::vec3 light) {
                                        if (!real.occluded(from, towards, 0.0f, tMax)) emittedWithout = light;
                                    });
        }
        shared.sampleLights(hit, wo, sampler, intoBoth(directWith, directWithout));
        p.radiance += p.throughput * (directWith + emittedWith);
        without += p.throughput * (directWithout + emittedWithout);
        const bool lastBounce = p.bounce + 1 >= shared.settings_.maxBounces;
        const float uLobe = sampler.uniform();
        const glm::vec2 u = sampler.uniform2();
        const float uRoulette = sampler.uniform();
        const BrdfSample s = sampleBrdf(hit.surface, hit.normal, wo, uLobe, u.x, u.y);
        if (!s.valid()) break;
        const glm::vec3 from = shared.offsetOrigin(hit, s.wi);
        if (lastBounce) {
            const RayHit next = with_.rays_.intersect(from, s.wi);
            p.radiance += p.throughput * with_.lastBounceLight(hit, s, next);
            without += p.throughput *
                       without_.lastBounceLight(hit, s, next.isVirtual ? real.intersect(from, s.wi) : next);
            break;
        }
        const glm::vec3 position = hit.position;  // p.hit is replaced below
        if (!shared.scatter(p, s, uRoulette)) break;
        const RayHit next = with_.rays_.intersect(from, p.direction);
        if (next.isVirtual) {
            // The paths part: each continues from here with the same random numbers.
            PathState apart = p;
            apart.radiance = without;
            apart.hit = real.intersect(from, p.direction);
            apart.radiance += apart.throughput * shared.lightsAlong(position, s, apart.hit);
            p.radiance += p.throughput * shared.lightsAlong(position, s, next);
            if (!apart.hit.hit() && shared.environment_)
                apart.radiance += apart.throughput * shared.environment_->radiance(apart.direction) *
                                  powerHeuristic(s.pdf, shared.environment_->pdf(apart.direction));
            ++apart.bounce;
            Sampler samplerWithout = sampler;
            without_.trace(apart, samplerWithout);
            without = apart.radiance;
            p.hit = next;
            ++p.bounce;
            with_.trace(p, sampler);
            break;
        }
        p.hit = next;
        const glm::vec3 lamps = p.throughput * shared.lightsAlong(position, s, next);
        p.radiance += lamps;
        without += lamps;
        if (!p.hit.hit() && shared.environment_) {
            const glm::vec3 sky = p.throughput * shared.environment_->radiance(p.direction) *
                                  powerHeuristic(s.pdf, shared.environment_->pdf(p.direction));
            p.radiance += sky;
            without += sky;
        }
    }
    r.with = p.radiance;
    r.without = without;
    return r;
}

namespace {

// Per-pixel sums over the samples taken so far, in double so that thousands of samples add up exactly enough.
struct PixelSums {
    glm::dvec3 with{0.0}, without{0.0};
    glm::dvec3 object{0.0};  // `with` of the samples whose first hit is virtual
    glm::dvec3 change{0.0};  // with - without of the other samples
    int virtualSamples = 0;
    // As ReferenceSums holds them: ReferenceSums::kValuesPerPixel values.
    void write(double* v) const {
        for (int c = 0; c < 3; ++c)
            v[c] = with[c], v[3 + c] = without[c], v[6 + c] = object[c], v[9 + c] = change[c];
        v[12] = virtualSamples;
    }
    static PixelSums read(const double* v) {
        PixelSums s;
        for (int c = 0; c < 3; ++c)
            s.with[c] = v[c], s.without[c] = v[3 + c], s.object[c] = v[6 + c], s.change[c] = v[9 + c];
        s.virtualSamples = static_cast<int>(v[12]);
        return s;
    }
};

glm::vec3 toVec3(glm::dvec3 v) {
    return glm::vec3(v);
}

ReferenceOutput assemble(const Scene& scene, std::span<const PixelSums> sums, int samples) {
    const int w = scene.camera.width, h = scene.camera.height;
    ReferenceOutput out;
    out.with = Image(w, h, 3);
    out.without = Image(w, h, 3);
    GBuffer coverage;  // only the coverage is read by the composite
    coverage.width = w;
    coverage.height = h;
    coverage.object.resize(sums.size());
    coverage.coverage.assign(sums.size(), 0.0f);
    std::vector<glm::vec3> objectRadiance(sums.size()), realChange(sums.size());
    const double n = std::max(samples, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = static_cast<size_t>(y) * w + x;
            const PixelSums& s = sums[i];
            out.with.setRgb(x, y, toVec3(s.with / n));
            out.without.setRgb(x, y, toVec3(s.without / n));
            const int realSamples = samples - s.virtualSamples;
            coverage.coverage[i] = static_cast<float>(s.virtualSamples / n);
            objectRadiance[i] =
                s.virtualSamples > 0 ? toVec3(s.object / double(s.virtualSamples)) : glm::vec3(0);
            realChange[i] = realSamples > 0 ? toVec3(s.change / double(realSamples)) : glm::vec3(0);
        }
    sanitize(out.with);
    sanitize(out.without);
    out.background = scene.background ? *scene.background : out.without;
    CompositeImages images = differentialComposite(out.background, coverage, objectRadiance, realChange);
    out.composite = std::move(images.composite);
    out.objectMask = std::move(images.objectMask);
    out.delta = std::move(images.delta);
    out.samplesPerPixel = samples;
    return out;
}

// The pixels' sums as a ReferenceSums of `samples` samples.
void writeSums(std::span<const PixelSums> sums, int w, int h, int samples, ReferenceSums& out) {
    out.width = w;
    out.height = h;
    out.samples = samples;
    out.values.resize(sums.size() * ReferenceSums::kValuesPerPixel);
    for (size_t i = 0; i < sums.size(); ++i) sums[i].write(&out.values[i * ReferenceSums::kValuesPerPixel]);
}

}  // namespace

ReferenceOutput renderReference(const Scene& scene, const ReferenceOptions& options,
                                const ReferenceProgress& onPass, const ReferenceSnapshot& onSnapshot,
                                const ReferenceSums* from) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    const Camera& camera = scene.camera;
    const RayScene all(scene, SceneContent::RealAndVirtual);
    const RayScene realOnly(scene, SceneContent::RealOnly);
    PathSettings settings;
    settings.rouletteStartBounce = options.rouletteStartBounce;
    settings.maxBounces = std::max(options.maxBounces, 1);
    settings.rayOffset =
        kRayOffsetScale * std::max(all.bounds().empty() ? 1.0f : all.bounds().maxExtent(), 1e-3f);
    const AreaLights allEmitters(scene, SceneContent::RealAndVirtual);
    const AreaLights realEmitters(scene, SceneContent::RealOnly);
    std::optional<EnvironmentSampler> environment;
    if (scene.environment) environment.emplace(*scene.environment);
    const EnvironmentSampler* sampler = environment ? &*environment : nullptr;
    const PathTracer withTracer(all, allEmitters, scene.lights, settings, sampler);
    const PathTracer withoutTracer(realOnly, realEmitters, scene.lights, settings, sampler);
    const RayScene objects(scene, SceneContent::VirtualOnly);
    const DifferentialPathTracer tracer(withTracer, withoutTracer, objects);

    const int w = camera.width, h = camera.height;
    std::vector<PixelSums> sums(static_cast<size_t>(w) * h);
    const glm::vec3 eye = camera.position();
    const int total = std::max(options.samplesPerPixel, 1);
    int done = 0;
    if (from && from->fits(camera) && from->samples < total) {
        for (size_t i = 0; i < sums.size(); ++i)
            sums[i] = PixelSums::read(&from->values[i * ReferenceSums::kValuesPerPixel]);
        done = from->samples;
    }
    double lastCheckpoint = 0.0;  // seconds
    while (done < total) {
        const int sample = done;
        parallelFor(0, h, kRowGrain, [&](int64_t y) {
            for (int x = 0; x < w; ++x) {
                const size_t i = static_cast<size_t>(y) * w + x;
                Sampler pixelSampler(i, static_cast<uint64_t>(sample), options.seed);
                const glm::vec2 jitter = pixelSampler.uniform2();
                const float jx = jitter.x, jy = jitter.y;
                const glm::vec3 dir = glm::normalize(camera.rayDirection(x + jx, static_cast<float>(y) + jy));
                const RayHit first = all.intersect(eye, dir);
                // The same random numbers for both paths: their difference is the object's effect alone.
                auto [with, without] = tracer.radiance(eye, dir, first, pixelSampler);
                if (!isFinite(with) || !isFinite(without)) with = without = glm::vec3(0.0f);  // never NaN
                PixelSums& s = sums[i];
                s.with += glm::dvec3(with);
                s.without += glm::dvec3(without);
                if (first.hit() && first.isVirtual) {
                    s.object += glm::dvec3(with);
                    ++s.virtualSamples;
                } else {
                    s.change += glm::dvec3(with) - glm::dvec3(without);
                }
            }
        });
        ++done;
        const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
        const bool snapshot = std::find(options.snapshotSamples.begin(), options.snapshotSamples.end(),
                                        done) != options.snapshotSamples.end();
        const bool checkpoint =
            options.checkpointSeconds > 0.0 && seconds - lastCheckpoint >= options.checkpointSeconds;
        if (onSnapshot && done < total && (snapshot || checkpoint)) {
            ReferenceOutput soFar = assemble(scene, sums, done);
            soFar.totalMs = 1000.0 * seconds;
            if (checkpoint) {
                writeSums(sums, w, h, done, soFar.sums);
                lastCheckpoint = seconds;
            }
            onSnapshot(soFar);
        }
        if (onPass) onPass(done, total, seconds);
        if (options.timeLimitSeconds > 0.0 && seconds >= options.timeLimitSeconds) break;
    }
    ReferenceOutput out = assemble(scene, sums, done);
    out.totalMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    writeSums(sums, w, h, done, out.sums);
    return out;
}

}  // namespace deltagi
