#include "pipeline/shading.h"

#include <numbers>

#include "core/brdf.h"
#include "core/brdf_sampling.h"
#include "core/lights.h"
#include "core/parallel.h"
#include "core/sampling.h"

namespace deltagi {

namespace {

constexpr int64_t kPointGrain = 256;
// A shadow cone stops this many cone diameters short of a point or spot light: trilinear samples of a mip
// level reach one voxel of that level beyond the cone, and a cone reaching the lamp would read the surfaces
// around it (a lamp set into a ceiling would shadow everything).
constexpr float kShadowConeStopDiameters = 1.5f;
// A glossy lobe whose Phong exponent n and the light's angular radius R have n R^2 above this (the disk more
// than about as wide as the lobe) is averaged over the light's disk by a kDiskSide x kDiskSide quadrature:
// the disk then makes a flat-topped highlight that no widened lobe follows (ggxAlphaOverLight and
// phongLobeOverLight hold within 12-20 % of the peak only while the disk is at most about twice the lobe's
// width). Quality suite's cornell-textured (a gilded vase under a sphere light), object_rel_rmse: 0.293 with
// the G-buffer's finer grids (PixelSamples::fine) alone, 0.243 with this too (0.467 with this alone: sharper
// highlights alias more over 2 x 2 samples).
constexpr float kDiskQuadratureSpread = 1.0f;
constexpr int kDiskSide = 3;
// A disk across a glossy point's horizon: its part above, a cap as thin as a sliver, by a finer quadrature
// (pixels along the light's terminator; 3 x 3 light a grazing glaze under a disk half a radius below it at a
// fifth of the truth). A matte point's takes the exact sum instead (horizonCosine).
constexpr int kHorizonDiskSide = 12;
// Where the mirror direction falls on the disk (or within kHighlightReach lobe widths of it), a lobe much
// narrower than the disk makes a flat-topped highlight with a sharp edge, which 3 x 3 lobes, each widened
// over a third of the disk, round off (a glaze, GGX alpha 0.0144, under a lamp 0.22 rad wide: 1.2-1.3
// times the truth at the highlight's centre, 0.5-0.75 near its edge, 0.22 at 75 degrees). There the
// quadrature takes cells about as wide as the lobe (one lobe half-width each), up to kMaxDiskSide a side.
constexpr float kHighlightReach = 3.0f;
constexpr int kMaxDiskSide = 16;

// The Phong exponent of a glossy lobe, for the test above at every shaded sample: Phong's own; for GGX the
// small-angle limit of ggxPhongExponent, 2 ln 2 / (1.287 alpha)^2 = 0.837 / alpha^2, without its
// trigonometry (which cost the textured torus's shading a third of its time); 4 % above it at alpha 0.16, 10
// % at 0.25 (wider lobes pass the test only under lights several times wider still).
float lobeExponent(const SurfaceMaterial& m) {
    if (m.model != MaterialModel::MetallicRoughness) return m.phongExponent();
    const float alpha = std::max(m.roughness * m.roughness, 1e-4f);
    return 0.837f / (alpha * alpha);
}

// The mean of max(cos, 0) over a sphere light's disk of angular radius asin(sinSigma) whose centre is at
// cosTheta from the normal, as a fraction of the disk's projected solid angle pi sin^2(sigma): the cosine
// a matte point takes in place of cosTheta, the disk clipped by its horizon. Over the horizon's reach
// (|cosTheta| < sinSigma) the integral of the cosine over the part of the cap above the horizon, in closed
// form (the sphere's clipped form factor, Snyder 1996 and Lagarde & de Rousiers 2014); cosTheta clamped at
// 0 elsewhere, where it is exact.
float horizonCosine(float cosTheta, float sinSigma) {
    const float s2 = sinSigma * sinSigma;
    if (cosTheta * cosTheta >= s2) return std::max(cosTheta, 0.0f);
    const float sinTheta = std::sqrt(std::max(1.0f - cosTheta * cosTheta, 1e-12f));
    const float x = std::sqrt(std::max(1.0f / s2 - 1.0f, 0.0f));
    const float y = std::clamp(-x * cosTheta / sinTheta, -1.0f, 1.0f);
    const float r = sinTheta * std::sqrt(1.0f - y * y);
    const float e = (cosTheta * std::acos(y) - x * r) * s2 + std::atan2(r, x);
    return std::max(e, 0.0f) / (std::numbers::pi_v<float> * s2);
}

// The side of the disk's quadrature for a glossy lobe of Phong exponent `exponent` at `point` under a disk of
// angular radius `lightAngle` around `toLight`: kDiskSide, or where the point sees the highlight, cells about
// as wide as the lobe (its half-width at half maximum, 1.18 / sqrt(n)).
int diskSide(const SurfacePoint& point, glm::vec3 toLight, float exponent, float lightAngle) {
    const float halfWidth = 1.18f / std::sqrt(exponent);
    const glm::vec3 mirror = glm::reflect(-point.toEye, point.normal);
    const float offCentre = std::acos(std::clamp(glm::dot(mirror, toLight), -1.0f, 1.0f));
    if (offCentre > lightAngle + kHighlightReach * halfWidth) return kDiskSide;
    const int side = static_cast<int>(std::ceil(lightAngle / halfWidth));
    return std::clamp(side, kDiskSide, kMaxDiskSide);
}

}  // namespace

float shadowFactor(const ShadowOcclusion& o, ShadowMode mode) {
    switch (mode) {
        case ShadowMode::Shaded:
            return 1.0f - o.combined;
        case ShadowMode::SceneOnly:
            return 1.0f - o.scene;
        case ShadowMode::DeltaShadow:
            return o.scene - o.combined;
        case ShadowMode::DeltaSingleVisibility:
            return -o.combined;
    }
    return 0.0f;
}

std::vector<ShadowOcclusion> traceShadowCones(std::span<const SurfacePoint> points,
                                              std::span<const Light> lights,
                                              const VisibilityVolumes& visibility, const Options& options,
                                              bool objectShadowOnly, std::span<const uint32_t> pixels,
                                              SceneOcclusionCache* sceneCache) {
    std::vector<ShadowOcclusion> out(points.size() * lights.size());
    if (sceneCache && sceneCache->known.size() != out.size()) {
        sceneCache->occlusion.assign(out.size(), 0.0f);
        sceneCache->known.assign(out.size(), 0);
    }
    if (lights.empty() || (!visibility.scene && !visibility.object)) return out;
    const ConeTraceSettings settings = coneTraceSettings(options.trace);
    const VolumeRegion& region = visibility.scene ? visibility.scene->region() : visibility.object->region();
    const float defaultTan = std::tan(0.5f * glm::radians(options.shadow.apertureDeg));
    forEachValidPoint(points, pixels, kPointGrain, [&](int64_t i) {
        const SurfacePoint& p = points[i];
        for (size_t l = 0; l < lights.size(); ++l) {
            const LightSample s = sampleLight(lights[l], p.position);
            if (glm::dot(s.wi, p.normal) <= 0.0f || s.irradiance == glm::vec3(0.0f)) continue;
            const float tanHalf = lights[l].radius > 0.0f && std::isfinite(s.distance)
                                      ? lights[l].radius / s.distance
                                  : lights[l].angularRadius > 0.0f ? std::tan(lights[l].angularRadius)
                                                                   : defaultTan;
            Cone cone;
            cone.tanHalfAngle = tanHalf;
            cone.origin = coneOrigin(p.position, p.normal, s.wi, region, settings);
            cone.direction = s.wi;
            cone.maxDistance = std::isfinite(s.distance)
                                   ? s.distance / (1.0f + kShadowConeStopDiameters * 2.0f * tanHalf)
                                   : s.distance;
            cone.jitter = hashToUnit(i, static_cast<uint32_t>(l));
            const size_t k = i * lights.size() + l;
            if (!objectShadowOnly) {
                out[k] = traceShadowCone(cone, visibility, settings);
                continue;
            }
            const float object = traceObjectOcclusion(cone, visibility, settings);
            if (object == 0.0f) continue;
            float scene;
            if (sceneCache && sceneCache->known[k]) {
                scene = sceneCache->occlusion[k];
            } else {
                scene = traceSceneOcclusion(cone, visibility, settings);
                if (sceneCache) sceneCache->occlusion[k] = scene, sceneCache->known[k] = 1;
            }
            out[k] = {scene, object, scene + object - scene * object};
        }
    });
    return out;
}

namespace {

// The light of `cones` (relit: the change of the incoming light with the objects, traceLightChangeCones;
// otherwise the light, traceLightCones), traced together in SIMD lanes.
void traceBatch(std::span<const Cone> cones, const MipVolume& light, const VisibilityVolumes& visibility,
                const ConeTraceSettings& settings, const MipVolume* fullLight, const MipVolume* objectLight,
                std::span<glm::vec3> out) {
    if (fullLight)
        traceLightChangeCones(cones, *fullLight, light, visibility, settings, objectLight, out);
    else
        traceLightCones(cones, light, visibility, settings, out);
}

}  // namespace

std::vector<glm::vec3> traceDiffuseCones(std::span<const SurfacePoint> points, const MipVolume& light,
                                         const VisibilityVolumes& visibility, const Options& options,
                                         std::span<const uint32_t> pixels, const MipVolume* fullLight,
                                         const MipVolume* objectLight, bool objectLightByRays,
                                         std::optional<float> apertureDeg) {
    std::vector<glm::vec3> out(points.size(), glm::vec3(0.0f));
    ConeTraceSettings settings = coneTraceSettings(options.trace);
    settings.objectLightByRays = objectLightByRays;
    const DiffuseConeSet cones =
        makeDiffuseCones(options.diffuse.count, apertureDeg.value_or(options.diffuse.apertureDeg));
    const size_t perPoint = cones.directions.size();
    forEachValidPointGroup(points, pixels, kPointGrain, [&](std::span<const int64_t> group) {
        // Every cone of the group's points, traced together.
        std::vector<int64_t> traced;
        std::vector<Cone> batch;
        batch.reserve(group.size() * perPoint);
        for (const int64_t i : group) {
            const SurfacePoint& p = points[i];
            if (p.surface.diffuse == glm::vec3(0.0f)) continue;
            traced.push_back(i);
            appendDiffuseCones(batch, cones, p.position, p.normal, light.region(), settings,
                               static_cast<uint64_t>(i), 1000u);
        }
        std::vector<glm::vec3> arriving(batch.size());
        traceBatch(batch, light, visibility, settings, fullLight, objectLight, arriving);
        for (size_t j = 0; j < traced.size(); ++j)
            out[traced[j]] = diffuseConesLight(cones, &arriving[j * perPoint]);
    });
    return out;
}

std::vector<glm::vec3> traceSpecularCones(std::span<const SurfacePoint> points, const MipVolume& light,
                                          const VisibilityVolumes& visibility, const Options& options,
                                          std::span<const uint32_t> pixels, const MipVolume* fullLight,
                                          const MipVolume* objectLight) {
    std::vector<glm::vec3> out(points.size(), glm::vec3(0.0f));
    const ConeTraceSettings settings = coneTraceSettings(options.trace);
    forEachValidPointGroup(points, pixels, kPointGrain, [&](std::span<const int64_t> group) {
        std::vector<int64_t> traced;
        std::vector<Cone> batch;
        for (const int64_t i : group) {
            const SurfacePoint& p = points[i];
            if (p.surface.specular == glm::vec3(0.0f)) continue;
            traced.push_back(i);
            Cone& cone = batch.emplace_back();
            cone.direction = glm::normalize(glm::reflect(-p.toEye, p.normal));
            cone.origin = coneOrigin(p.position, p.normal, cone.direction, light.region(), settings);
            cone.tanHalfAngle = specularConeTanHalfAngle(
                p.surface.phongExponent(), options.specular.minApertureDeg, options.specular.maxApertureDeg);
            cone.jitter = hashToUnit(i, 2000u);
        }
        std::vector<glm::vec3> arriving(batch.size());
        traceBatch(batch, light, visibility, settings, fullLight, objectLight, arriving);
        for (size_t j = 0; j < traced.size(); ++j) out[traced[j]] = arriving[j];
    });
    return out;
}

namespace {

// The quadrature over a light's disk of a lobe narrower than it: each point's lobe widened over its cell of
// the disk (its angular radius over `side`). cell(wi, value) for every cell, `value` the BRDF times the
// cosine (zero below the horizon). Kept out of line: most points never come here.
template <typename Cell>
[[gnu::noinline]] void forEachDiskCell(const SurfacePoint& point, glm::vec3 toLight, float lightAngle,
                                       int side, Cell&& cell) {
    const glm::mat3 aroundLight = frameAround(toLight);
    const float spread = std::tan(lightAngle);
    for (int a = 0; a < side; ++a)
        for (int b = 0; b < side; ++b) {
            const glm::vec2 onDisk = spread * concentricDisk((a + 0.5f) / side, (b + 0.5f) / side);
            const glm::vec3 wi = glm::normalize(aroundLight * glm::vec3(onDisk, 1.0f));
            const float cosine = glm::dot(wi, point.normal);
            cell(wi, cosine > 0.0f
                         ? evalBrdf(point.surface, point.normal, point.toEye, wi, lightAngle / side) * cosine
                         : glm::vec3(0.0f));
        }
}

// How directRadiance takes a light at a point.
struct DirectLightPlan {
    LightSample sample;
    float horizon = 0.0f;     // the sine of the light's angular radius: how far below the horizon it reaches
    float lightAngle = 0.0f;  // its angular radius
    int diskSide = 0;         // > 0: the glossy lobe by a diskSide x diskSide quadrature over the disk
    float exponent = 0.0f;    // with one: the lobe's Phong exponent (lobeExponent)
    bool dark = false;        // the whole disk below the horizon
};

DirectLightPlan planDirectLight(const SurfacePoint& point, const Light& light) {
    DirectLightPlan plan;
    plan.sample = sampleLight(light, point.position);
    const LightSample& s = plan.sample;
    const float cosTheta = glm::dot(s.wi, point.normal);
    // A sphere light's glossy highlight is as wide as its disk (the path tracer samples the disk): its
    // angular radius, and its sine, how far below the horizon the disk reaches.
    const bool directional = light.type == Light::Type::Directional;
    plan.horizon = directional                                ? std::sin(light.angularRadius)
                   : light.radius > 0.0f && s.distance > 0.0f ? std::min(light.radius / s.distance, 1.0f)
                                                              : 0.0f;
    plan.lightAngle = directional ? light.angularRadius : std::asin(plan.horizon);
    // A disk across the horizon lights the point with its part above it (horizonCosine, or the quadrature
    // for a glossy lobe: at grazing incidence a glaze reflects most).
    if (!(cosTheta > -plan.horizon)) {
        plan.dark = true;
        return plan;
    }
    const SurfaceMaterial& m = point.surface;
    if (!m.glossy()) return plan;
    const float exponent = lobeExponent(m);
    if (cosTheta < plan.horizon) {
        plan.diskSide = kHorizonDiskSide;
        plan.exponent = exponent;
        return plan;
    }
    if (exponent * plan.lightAngle * plan.lightAngle > kDiskQuadratureSpread) {
        plan.diskSide = diskSide(point, s.wi, exponent, plan.lightAngle);
        plan.exponent = exponent;
    }
    return plan;
}

}  // namespace

glm::vec3 directRadiance(const SurfacePoint& point, const Light& light) {
    const DirectLightPlan plan = planDirectLight(point, light);
    if (plan.dark) return glm::vec3(0.0f);
    const LightSample& s = plan.sample;
    if (plan.diskSide > 0) {
        glm::vec3 sum(0.0f);
        forEachDiskCell(point, s.wi, plan.lightAngle, plan.diskSide,
                        [&](glm::vec3, glm::vec3 v) { sum += v; });
        return sum * (s.irradiance / static_cast<float>(plan.diskSide * plan.diskSide));
    }
    const SurfaceMaterial& m = point.surface;
    const float cosTheta = glm::dot(s.wi, point.normal);
    if (cosTheta < plan.horizon)
        return evalBrdf(m, point.normal, point.toEye, s.wi) * s.irradiance *
               horizonCosine(cosTheta, plan.horizon);
    return evalBrdf(m, point.normal, point.toEye, s.wi, plan.lightAngle) * s.irradiance * cosTheta;
}

void directLightCells(const SurfacePoint& point, const Light& light, float minLobeSpread,
                      std::vector<DirectLightCell>& cells) {
    cells.clear();
    const DirectLightPlan plan = planDirectLight(point, light);
    if (plan.dark || plan.diskSide == 0) return;
    if (plan.exponent * plan.lightAngle * plan.lightAngle < minLobeSpread) return;
    const LightSample& s = plan.sample;
    const float share = 1.0f / static_cast<float>(plan.diskSide * plan.diskSide);
    forEachDiskCell(point, s.wi, plan.lightAngle, plan.diskSide, [&](glm::vec3 wi, glm::vec3 v) {
        // The disk's plane is s.distance away along s.wi.
        cells.push_back({wi, s.distance / std::max(glm::dot(wi, s.wi), 1e-3f), v * s.irradiance * share});
    });
}

namespace {

// The direct light of `light` at `p`, or its mean over the valid points of `area` when there are any.
glm::vec3 directRadianceOver(const SurfacePoint& p, std::span<const SurfacePoint> area, const Light& light) {
    glm::vec3 sum(0.0f);
    int n = 0;
    for (const SurfacePoint& q : area) {
        if (!q.valid()) continue;
        sum += directRadiance(q, light);
        ++n;
    }
    return n > 0 ? sum / static_cast<float>(n) : directRadiance(p, light);
}

}  // namespace

std::vector<glm::vec3> combineLighting(std::span<const SurfacePoint> points, std::span<const Light> lights,
                                       std::span<const ShadowOcclusion> shadows, ShadowMode mode,
                                       std::span<const glm::vec3> diffuse,
                                       std::span<const glm::vec3> specular, const PixelRect* bounds,
                                       int width, const PixelSamples* samples,
                                       std::vector<glm::vec3>* indirect) {
    std::vector<glm::vec3> out(points.size(), glm::vec3(0.0f));
    if (indirect) indirect->assign(points.size(), glm::vec3(0.0f));
    // A rendered surface shows what it emits; a relit one only changes, and its emission is in the photo.
    const bool emits = mode == ShadowMode::Shaded || mode == ShadowMode::SceneOnly;
    auto shade = [&](size_t i) {
        const SurfacePoint& p = points[i];
        if (!p.valid()) return;
        glm::vec3 radiance = emits ? p.surface.emission : glm::vec3(0.0f);
        const std::span<const SurfacePoint> area =
            samples && mode == ShadowMode::Shaded ? samples->of(i, width) : std::span<const SurfacePoint>{};
        for (size_t l = 0; l < lights.size(); ++l) {
            // Relit surfaces mostly do not change: skip the BRDF where the factor is zero.
            const float factor = shadowFactor(shadows[i * lights.size() + l], mode);
            if (factor != 0.0f) radiance += directRadianceOver(p, area, lights[l]) * factor;
        }
        glm::vec3& reflected = indirect ? (*indirect)[i] : radiance;
        if (!diffuse.empty()) reflected += p.surface.diffuse * (p.surface.occlusion * diffuse[i]);
        if (!specular.empty()) {
            // Where the specular light is zero (most of a relit image) its reflectance is not looked up: the
            // zero, its sign too, is what the product would add.
            const glm::vec3 light = p.surface.occlusion * specular[i];
            reflected += light == glm::vec3(0.0f)
                             ? light
                             : p.surface.specularReflectance(glm::dot(p.normal, p.toEye)) * light;
        }
        out[i] = radiance;
    };
    if (!bounds) {
        parallelFor(0, static_cast<int64_t>(points.size()), 4096, [&](int64_t i) { shade(i); });
        return out;
    }
    parallelFor(bounds->y0, bounds->y1, 4, [&](int64_t y) {
        for (int x = bounds->x0; x < bounds->x1; ++x) shade(static_cast<size_t>(y) * width + x);
    });
    return out;
}

}  // namespace deltagi
