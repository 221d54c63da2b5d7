#include "core/surface_material.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/ggx.h"

namespace deltagi {

namespace {

template <typename T>
T interpolate(const std::vector<T>& values, glm::uvec3 tri, float u, float v) {
    return (1.0f - u - v) * values[tri.x] + u * values[tri.y] + v * values[tri.z];
}

// A triangle's corners as a textured lookup reads them, loaded once for the footprint, the texture
// coordinates and the normal map's frame: positions and texture coordinates of set 0.
struct Corners {
    glm::vec3 p0, p1, p2;
    glm::vec2 t0, t1, t2;
    Corners(const std::vector<glm::vec3>& positions, const std::vector<glm::vec2>& uvs, glm::uvec3 tri)
        : p0(positions[tri.x]),
          p1(positions[tri.y]),
          p2(positions[tri.z]),
          t0(uvs[tri.x]),
          t1(uvs[tri.y]),
          t2(uvs[tri.z]) {}
    // uvFootprintOn's factor times `footprint`.
    float uvFootprint(float footprint) const {
        const float area = glm::length(glm::cross(p1 - p0, p2 - p0));
        const glm::vec2 d1 = t1 - t0, d2 = t2 - t0;
        const float uvArea = std::abs(d1.x * d2.y - d2.x * d1.y);
        return area > 0.0f ? footprint * std::sqrt(uvArea / area) : 0.0f;
    }
    glm::vec2 uvAt(float u, float v) const { return (1.0f - u - v) * t0 + u * t1 + v * t2; }
};

// The material's base colour (Phong: albedo) at a point before its textures: times the vertex colours.
[[gnu::always_inline]] inline glm::vec3 untexturedBaseAt(const TriangleMesh& mesh, glm::uvec3 tri, float u,
                                                         float v) {
    glm::vec3 base = mesh.material.albedo;
    if (!mesh.colors.empty()) base *= interpolate(mesh.colors, tri, u, v);
    return base;
}

SurfaceMaterial fromFactors(const Material& m, glm::vec3 base, float metallic, float roughness) {
    SurfaceMaterial s;
    s.model = m.model;
    s.roughness = roughness;
    s.emission = m.emission;
    if (m.model == MaterialModel::MetallicRoughness) {
        s.diffuse = base * (1.0f - metallic);
        s.specular = glm::mix(glm::vec3(kGltfDielectricF0), base, metallic);
    } else {
        s.diffuse = base;
        s.specular = m.specular;
    }
    return s;
}

// The tangent-space normal map's normal at a point, in the frame of the shading normal `n`: the mesh's
// tangents where it has them, else the triangle's texture-coordinate derivative dp/du.
glm::vec3 mappedNormal(const TriangleMesh& mesh, glm::uvec3 tri, float u, float v, glm::vec3 n,
                       glm::vec3 texel, float scale, const Corners& corners) {
    glm::vec3 tangent;
    float handedness = 1.0f;
    float lengthScale = 1.0f;  // the tangent's length is this many times dp/du's
    if (!mesh.tangents.empty()) {
        const glm::vec4 t = interpolate(mesh.tangents, tri, u, v);
        tangent = glm::vec3(t);
        handedness = t.w < 0.0f ? -1.0f : 1.0f;
    } else {
        const bool set1 = mesh.material.normalTexture.texCoord == 1 && !mesh.uvs1.empty();
        const glm::vec3 e1 = corners.p1 - corners.p0, e2 = corners.p2 - corners.p0;
        const glm::vec2 d1 = set1 ? mesh.uvs1[tri.y] - mesh.uvs1[tri.x] : corners.t1 - corners.t0;
        const glm::vec2 d2 = set1 ? mesh.uvs1[tri.z] - mesh.uvs1[tri.x] : corners.t2 - corners.t0;
        const float det = d1.x * d2.y - d2.x * d1.y;
        if (!(std::abs(det) > 1e-20f)) return n;
        // dp/du and dp/dv up to the positive factor 1 / |det| (only their directions are used).
        const float sign = det < 0.0f ? -1.0f : 1.0f;
        lengthScale = std::abs(det);
        tangent = (e1 * d2.y - e2 * d1.y) * sign;
        const glm::vec3 bitangent = (e2 * d1.x - e1 * d2.x) * sign;
        // glTF's v runs down the image while its bitangent points up (+v in OpenGL's convention): the
        // texture's green channel points towards -dp/dv.
        handedness = glm::dot(glm::cross(n, tangent), -bitangent) < 0.0f ? -1.0f : 1.0f;
    }
    tangent -= n * glm::dot(n, tangent);
    const float length = glm::length(tangent);
    if (!(length > 1e-12f * lengthScale)) return n;
    tangent *= 1.0f / length;
    const glm::vec3 bitangent = handedness * glm::cross(n, tangent);
    glm::vec3 local = texel * 2.0f - 1.0f;
    local.x *= scale;
    local.y *= scale;
    const glm::vec3 mapped = local.x * tangent + local.y * bitangent + local.z * n;
    const float mappedLength = glm::length(mapped);
    return mappedLength > 1e-12f && std::isfinite(mappedLength) ? mapped * (1.0f / mappedLength) : n;
}

}  // namespace

// GGX: the exponent whose cos^n falls to half at the GGX lobe's half-maximum (ggx.h).
float SurfaceMaterial::ggxPhongExponentOf(float perceptualRoughness) {
    return ggxPhongExponent(perceptualRoughness * perceptualRoughness);
}

float phongDirectionalAlbedo(float exponent, float nDotV) {
    const float mu = std::clamp(nDotV, 0.0f, 1.0f);
    const auto overHorizon = [mu](float n) {
        const float sigma = 1.0f / std::sqrt(n + 1.0f), z = mu / sigma;
        // The lobe wholly above the horizon (to 1e-5): its mean cosine.
        if (z > 4.5f) return mu;
        const float cdf = 0.5f * std::erfc(-z * std::numbers::sqrt2_v<float> * 0.5f);
        const float pdf = std::exp(-0.5f * z * z) *
                          (0.5f * std::numbers::sqrt2_v<float> * std::numbers::inv_sqrtpi_v<float>);
        return std::min(1.0f, mu * cdf + sigma * pdf);
    };
    const float n = std::max(exponent, 0.0f);
    if (n >= 1.0f) return overHorizon(n);
    return (1.0f - n) * 0.5f * (1.0f + mu) + n * overHorizon(1.0f);
}

glm::vec3 SurfaceMaterial::ggxSpecularReflectance(float nDotV) const {
    const glm::vec4 c0(-1.0f, -0.0275f, -0.572f, 0.022f), c1(1.0f, 0.0425f, 1.04f, -0.04f);
    const glm::vec4 r = roughness * c0 + c1;
    const float a004 = std::min(r.x * r.x, std::exp2(-9.28f * std::clamp(nDotV, 0.0f, 1.0f))) * r.x + r.y;
    const float scale = -1.04f * a004 + r.z, bias = 1.04f * a004 + r.w;
    return glm::clamp(specular * scale + bias, glm::vec3(0.0f), glm::vec3(1.0f));
}

SurfaceMaterial constantSurfaceMaterial(const Material& m) {
    return fromFactors(m, m.albedo, m.metallic, m.roughness);
}

bool variesOverSurface(const TriangleMesh& mesh) {
    return !mesh.colors.empty() || (mesh.material.textured() && !mesh.uvs.empty());
}

glm::vec2 textureCoordinatesAt(const TriangleMesh& mesh, unsigned triangle, float u, float v, int set) {
    const std::vector<glm::vec2>& uvs = set == 1 && !mesh.uvs1.empty() ? mesh.uvs1 : mesh.uvs;
    if (uvs.empty()) return glm::vec2(0.0f);
    return interpolate(uvs, mesh.triangles[triangle], u, v);
}

namespace {

// surfaceMaterialAtUv of a textured mesh with texture coordinates, its triangle's corners loaded.
SurfaceMaterial texturedMaterialAt(const TriangleMesh& mesh, unsigned triangle, glm::uvec3 tri,
                                   const Corners& corners, float u, float v, float uvFootprint,
                                   glm::vec3* normal) {
    const Material& m = mesh.material;
    glm::vec3 base = untexturedBaseAt(mesh, tri, u, v);
    // Each texture coordinate set interpolated once, when a texture reads it; the texels' places and weights
    // worked out once for the maps of one size, set and sampler (a glTF material's usually are).
    glm::vec2 uvs[2];
    bool interpolated[2] = {false, false};
    const TextureSlot* located = nullptr;
    Texture::Lookup where;
    auto lookup = [&](const TextureSlot& slot) {
        const int set = slot.texCoord == 1 ? 1 : 0;
        if (!interpolated[set]) {
            uvs[set] = set == 0 ? corners.uvAt(u, v) : textureCoordinatesAt(mesh, triangle, u, v, 1);
            interpolated[set] = true;
        }
        if (!located || located->texCoord != slot.texCoord || !(located->sampler == slot.sampler) ||
            !located->texture->sameSize(*slot.texture)) {
            slot.texture->locate(uvs[set], uvFootprint, slot.sampler, where);
            located = &slot;
        }
        return slot.texture->read(where);
    };
    float metallic = m.metallic, roughness = m.roughness;
    if (m.baseColorTexture) base *= glm::vec3(lookup(m.baseColorTexture));
    if (m.metallicRoughnessTexture) {
        const glm::vec4 t = lookup(m.metallicRoughnessTexture);
        metallic *= t.z;  // glTF: blue holds metallic, green roughness
        roughness *= t.y;
    }
    if (m.roughnessTexture) roughness *= lookup(m.roughnessTexture).x;
    if (m.shininessTexture && m.model == MaterialModel::Phong) {
        // MTL: the map multiplies the exponent Ns; roughness and Ns correspond as in phongExponent().
        const float r = std::max(roughness, 1e-3f);
        const float exponent = std::max(2.0f / (r * r) - 2.0f, 0.0f) * lookup(m.shininessTexture).x;
        roughness = std::sqrt(2.0f / (exponent + 2.0f));
    }
    SurfaceMaterial s =
        fromFactors(m, base, std::clamp(metallic, 0.0f, 1.0f), std::clamp(roughness, 0.0f, 1.0f));
    if (m.specularTexture && m.model == MaterialModel::Phong)
        s.specular *= glm::vec3(lookup(m.specularTexture));
    if (m.emissiveTexture) s.emission *= glm::vec3(lookup(m.emissiveTexture));
    if (!normal) return s;
    if (m.occlusionTexture) s.occlusion = 1.0f + m.occlusionStrength * (lookup(m.occlusionTexture).x - 1.0f);
    if (m.normalTexture)
        *normal = mappedNormal(mesh, tri, u, v, *normal, glm::vec3(lookup(m.normalTexture)), m.normalScale,
                               corners);
    return s;
}

}  // namespace

SurfaceMaterial surfaceMaterialAt(const TriangleMesh& mesh, unsigned triangle, float u, float v,
                                  float footprint, glm::vec3* normal) {
    if (!mesh.material.textured() || mesh.uvs.empty())
        return surfaceMaterialAtUv(mesh, triangle, u, v, 0.0f, normal);
    const glm::uvec3 tri = mesh.triangles[triangle];
    const Corners corners(mesh.positions, mesh.uvs, tri);
    const float uvFootprint = footprint > 0.0f ? corners.uvFootprint(footprint) : 0.0f;
    return texturedMaterialAt(mesh, triangle, tri, corners, u, v, uvFootprint, normal);
}

float uvFootprintOn(const std::vector<glm::vec3>& positions, const std::vector<glm::vec2>& uvs,
                    glm::uvec3 tri, float footprint) {
    return Corners(positions, uvs, tri).uvFootprint(footprint);
}

SurfaceMaterial surfaceMaterialAtUv(const TriangleMesh& mesh, unsigned triangle, float u, float v,
                                    float uvFootprint, glm::vec3* normal) {
    const Material& m = mesh.material;
    if (!variesOverSurface(mesh)) return constantSurfaceMaterial(m);
    const glm::uvec3 tri = mesh.triangles[triangle];
    if (!m.textured() || mesh.uvs.empty())
        return fromFactors(m, untexturedBaseAt(mesh, tri, u, v), m.metallic, m.roughness);
    return texturedMaterialAt(mesh, triangle, tri, Corners(mesh.positions, mesh.uvs, tri), u, v, uvFootprint,
                              normal);
}

glm::vec3 triangleEmission(const TriangleMesh& mesh, unsigned triangle) {
    const Material& m = mesh.material;
    if (!m.emissiveTexture || mesh.uvs.empty()) return m.emission;
    const glm::uvec3 tri = mesh.triangles[triangle];
    const glm::vec3 a = mesh.positions[tri.x];
    const float area = 0.5f * glm::length(glm::cross(mesh.positions[tri.y] - a, mesh.positions[tri.z] - a));
    const glm::vec2 uv =
        textureCoordinatesAt(mesh, triangle, 1.0f / 3.0f, 1.0f / 3.0f, m.emissiveTexture.texCoord);
    float uvFootprint = 0.0f;
    if (area > 0.0f) {
        const glm::vec2 d1 = mesh.uvs[tri.y] - mesh.uvs[tri.x], d2 = mesh.uvs[tri.z] - mesh.uvs[tri.x];
        uvFootprint = std::sqrt(0.5f * std::abs(d1.x * d2.y - d2.x * d1.y));
    }
    return m.emission * glm::vec3(m.emissiveTexture.sample(uv, uvFootprint));
}

bool surfacePresentAt(const TriangleMesh& mesh, unsigned triangle, float u, float v) {
    const Material& m = mesh.material;
    if (m.alphaMode != AlphaMode::Mask) return true;
    float alpha = m.opacity;
    if (m.baseColorTexture && !mesh.uvs.empty())
        alpha *= m.baseColorTexture
                     .sample(textureCoordinatesAt(mesh, triangle, u, v, m.baseColorTexture.texCoord), 0.0f)
                     .w;
    return alpha >= m.alphaCutoff;
}

}  // namespace deltagi
