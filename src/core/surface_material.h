// A material's values at one point of a surface: its textures looked up at the point's texture coordinates,
// its vertex colours interpolated, its normal map applied. What the BRDF (brdf.h), the G-buffer, the
// reflective shadow maps, voxelization and the path tracer use, so that every stage sees the same texel.
#pragma once

#include <algorithm>

#include <glm/glm.hpp>

#include "deltagi/scene.h"

namespace deltagi {

// The directional albedo of the normalized Phong lobe of brdf.h, (n + 2) / (2 pi) cos^n of the angle to the
// mirror direction, seen at n.v = `nDotV`: its integral times cos(theta_i) over the hemisphere. Where the
// lobe lies above the horizon that is the cosine's mean over the lobe, n.v; towards grazing views the horizon
// cuts off the lobe's part that would count negative. Taken as the mean of max(0, x) for x normal with mean
// n.v and deviation 1 / sqrt(n + 1), the lobe's angular width: within 0.04 of numerical integration for n >=
// 1 (0.007 for n >= 5); below 1, blended towards n = 0's (1 + n.v) / 2.
float phongDirectionalAlbedo(float exponent, float nDotV);

struct SurfaceMaterial {
    // The Lambertian part's reflectance: Phong's albedo; glTF's base colour * (1 - metallic).
    glm::vec3 diffuse{0.0f};
    // Phong: the glossy reflectance; MetallicRoughness: F0, the Fresnel reflectance at normal incidence,
    // mix(0.04, base colour, metallic).
    glm::vec3 specular{0.0f};
    // Phong: r, the lobe's width (Material::roughness); MetallicRoughness: glTF's perceptual roughness.
    float roughness = 1.0f;
    glm::vec3 emission{0.0f};
    float occlusion = 1.0f;  // the occlusion map's value (1: none); dims the indirect light only
    MaterialModel model = MaterialModel::Phong;

    bool emits() const { return emission != glm::vec3(0.0f); }
    bool glossy() const { return specular != glm::vec3(0.0f); }
    // What the light volumes reflect (see Material::volumeReflectance): diffuse plus glossy reflectance,
    // for MetallicRoughness diffuse + F0 (the specular lobe's reflectance at normal incidence).
    glm::vec3 volumeReflectance() const { return diffuse + specular; }
    // The exponent of the Phong lobe cos^n around the mirror direction that the specular cone stands for:
    // Phong's own (Material::phongExponent), or the one as wide as the GGX lobe's half-maximum.
    float phongExponent() const {
        if (model == MaterialModel::MetallicRoughness) return ggxPhongExponentOf(roughness);
        // Phong: the Blinn-Phong/Beckmann correspondence n = 2/r^2 - 2 (Material::phongExponent).
        const float r = std::max(roughness, 1e-3f);
        return std::max(2.0f / (r * r) - 2.0f, 0.0f);
    }
    // What the specular cone's radiance is weighted by, seen at n.v = `nDotV`: the lobe's directional albedo.
    // Phong: the glossy reflectance times the normalized lobe's (phongDirectionalAlbedo: about n.v, as the
    // path tracer's reflection dims towards grazing views). GGX: with Schlick's Fresnel, F0 * A + B (the
    // split-sum approximation), after Karis' analytic fit ("Physically Based Shading on Mobile", 2014): the
    // glancing Fresnel rise of a dielectric, and the energy a rough lobe loses.
    glm::vec3 specularReflectance(float nDotV) const {
        return model == MaterialModel::MetallicRoughness
                   ? ggxSpecularReflectance(nDotV)
                   : specular * phongDirectionalAlbedo(phongExponent(), nDotV);
    }

  private:
    // The GGX model's: the exponent as wide as the lobe's half-maximum (ggx.h), and the split-sum albedo.
    static float ggxPhongExponentOf(float perceptualRoughness);
    glm::vec3 ggxSpecularReflectance(float nDotV) const;
};

// Calls value(field) for every field of `m` that decides how it looks, one by one (Material has padding, so
// it cannot be hashed as bytes): for cache keys. Textures never change, so their addresses stand for them.
template <typename Value>
void visitMaterialFields(const Material& m, Value&& value) {
    value(m.albedo);
    value(m.specular);
    value(m.roughness);
    value(m.emission);
    value(m.model);
    value(m.metallic);
    value(m.opacity);
    value(m.alphaMode);
    value(m.alphaCutoff);
    value(m.normalScale);
    value(m.occlusionStrength);
    for (const TextureSlot* slot :
         {&m.baseColorTexture, &m.specularTexture, &m.roughnessTexture, &m.shininessTexture,
          &m.metallicRoughnessTexture, &m.normalTexture, &m.emissiveTexture, &m.occlusionTexture}) {
        value(slot->texture.get());
        value(slot->sampler.wrapS);
        value(slot->sampler.wrapT);
        value(slot->sampler.magFilter);
        value(slot->sampler.minFilter);
        value(slot->sampler.mipmaps);
        value(slot->texCoord);
    }
}

// The values of a material without textures and vertex colours (its factors).
SurfaceMaterial constantSurfaceMaterial(const Material& m);

// Whether looking up `mesh`'s material at a point needs its triangle and texture coordinates: textures or
// vertex colours. False: constantSurfaceMaterial(mesh.material) is the answer everywhere.
bool variesOverSurface(const TriangleMesh& mesh);

// The material of `mesh` at barycentric (u, v) of triangle `triangle` (Embree's: the point is
// (1 - u - v) a + u b + v c). `footprint`: the width in world units of the area the lookup stands for (a
// pixel's, a texel's), 0 for the finest texels; it selects the textures' mip levels through the triangle's
// texture-coordinate density. `normal`: the interpolated unit shading normal, oriented as the mesh's
// normals are; replaced by the normal-mapped one when the material has a normal map. Null: only what the
// light volumes need (reflectance and emission): the normal and occlusion maps are not looked up.
SurfaceMaterial surfaceMaterialAt(const TriangleMesh& mesh, unsigned triangle, float u, float v,
                                  float footprint, glm::vec3* normal);

// A footprint `footprint` world units wide on triangle `tri` of a mesh with `positions` and `uvs`, in
// texture coordinates: times the triangle's texture-coordinate density; 0 for a degenerate triangle.
float uvFootprintOn(const std::vector<glm::vec3>& positions, const std::vector<glm::vec2>& uvs,
                    glm::uvec3 tri, float footprint);

// surfaceMaterialAt with the footprint given in texture coordinates (1 = the texture's width) instead.
SurfaceMaterial surfaceMaterialAtUv(const TriangleMesh& mesh, unsigned triangle, float u, float v,
                                    float uvFootprint, glm::vec3* normal);

// The texture coordinates (set `set`, 0 or 1) at barycentric (u, v) of `triangle`; (0, 0) when the mesh has
// none.
glm::vec2 textureCoordinatesAt(const TriangleMesh& mesh, unsigned triangle, float u, float v, int set = 0);

// The emitted radiance of a triangle as the area lights sample it: the material's emission times its
// emissive texture's mean over the triangle (a lookup at the centroid filtered over the triangle's size).
// Where the texture varies within a triangle, the light sampled towards it is this mean, while a ray that
// hits the triangle sees the texel: the same on average.
glm::vec3 triangleEmission(const TriangleMesh& mesh, unsigned triangle);

// Whether an alpha-masked material's surface is there at a point: the base colour's alpha (factor times
// texture, finest texels) at least the cutoff. Always true for opaque materials.
bool surfacePresentAt(const TriangleMesh& mesh, unsigned triangle, float u, float v);

}  // namespace deltagi
