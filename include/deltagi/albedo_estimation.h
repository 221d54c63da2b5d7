// The real scene's diffuse albedo from the photo (after Debevec 1998, §6): nobody measured the real surfaces'
// reflectance, but the photo shows them lit, so that at a surface point seen in pixel p
//   albedo = pi * L_photo(p) / E(p),
// E the irradiance there. E depends on the other surfaces' albedo (the light they reflect onto the point), so
// the estimate is iterated: each pass computes E with the previous pass's albedos, starting from the scene's
// materials as given.
//
// E is path traced in the real scene alone (no virtual objects): a white Lambertian surface at the point
// reflects L = E / pi, so E = pi * PathTracer::radianceFromHit() with the material replaced by white -- the
// lights with shadow rays, the emitters and the environment map by next-event estimation, and cosine-
// weighted bounce rays into the real scene with its current albedos, combined by multiple importance sampling
// exactly as the reference renders. One camera ray through each pixel's centre finds the point.
//
// Only the diffuse part is estimated: a material's specular lobe (Phong "specular") is kept as it is, and
// the light it reflects towards the camera (path traced with the current estimates) is taken off the photo
// first. Textures of the real meshes are ignored (the base colour texture is dropped when the estimate is
// applied).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "deltagi/export.h"
#include "deltagi/scene.h"

DELTAGI_API_BEGIN
namespace deltagi {

enum class AlbedoGranularity {
    PerMesh,    // one RGB albedo per real mesh: the ratio of sums over its pixels, sum(pi L) / sum(E)
    PerVertex,  // one per vertex: each pixel's pi L and E splatted onto its triangle's vertices by
                // barycentric weight, the albedo the ratio of the vertex's sums; unseen vertices get the
                // mesh's overall estimate
};

struct AlbedoOptions {
    int iterations = 4;        // passes; each recomputes the irradiance with the previous pass's albedos
    int samplesPerPixel = 64;  // irradiance paths per pixel and pass
    AlbedoGranularity granularity = AlbedoGranularity::PerMesh;
    uint64_t seed = 0;            // the same seed gives the same estimate, whatever the thread count
    int rouletteStartBounce = 3;  // the path tracer's Russian roulette (reference.h)
    // Pixels at a mesh's silhouette or crease (a 4-neighbour's centre ray hits another surface, nothing, or a
    // face of the mesh turned by more than about 18 degrees) mix two surfaces in the photo, while the centre
    // sees one: left out, unless the mesh has no other pixel.
    bool skipEdgePixels = true;
    // Per real mesh, whether to estimate it (empty: all); the others keep their material and only light the
    // estimated ones.
    std::vector<bool> meshes;
};

struct MeshAlbedo {
    std::string name;
    bool estimated = true;  // false: not asked for (AlbedoOptions::meshes); `albedo` is the material's
    // The estimate, each channel in [0, 1 - specular] (Phong: energy conservation); per vertex: the mesh's
    // overall estimate (its ratio of sums). A mesh no pixel sees (or an emitter) keeps its material's albedo.
    glm::vec3 albedo{0.0f};
    std::vector<glm::vec3> vertexAlbedo;  // per vertex: one per position, in the same range; empty per mesh
    size_t pixelsUsed = 0;       // pixels whose centre ray hits the mesh (lit: E > 0), in the last pass
    size_t pixelsClamped = 0;    // of those, the pixels brighter than the largest albedo explains (pi L > E)
    size_t verticesSeen = 0;     // per vertex: vertices some used pixel splats onto
    size_t verticesClamped = 0;  // per vertex: vertices whose ratio exceeded 1 in some channel
    bool clamped = false;        // the mesh's overall ratio exceeded the largest albedo in some channel
    // The last pass's sums over the used pixels: sum(pi (L - L_specular)) and sum(E), for pooling meshes.
    glm::dvec3 reflectedSum{0.0};
    glm::dvec3 irradianceSum{0.0};
};

struct AlbedoEstimate {
    AlbedoGranularity granularity = AlbedoGranularity::PerMesh;
    std::vector<MeshAlbedo> meshes;  // one per Scene::real, in order
    // Per pass: the largest change of any mesh's overall albedo (any channel) from the previous pass (the
    // first: from the scene's materials). Shrinks as the interreflection converges.
    std::vector<float> changePerIteration;
    // Meshes where the photo is brighter than any albedo explains, and meshes no lit pixel shows.
    std::vector<std::string> warnings;
};

// Estimates the albedo of every real mesh (Scene::real) from `scene.background`. Throws InputError (naming
// the scene file and the key) when the scene has no background photo or one of another size than the
// camera's, no real mesh, or when the options are out of range (iterations or samples below 1).
AlbedoEstimate estimateAlbedo(const Scene& scene, const AlbedoOptions& options = {});

// Puts an estimate into the scene's real meshes (which must be those it was estimated for; meshes not
// estimated stay as they are): per mesh,
// material.albedo. Per vertex, material.albedo is the mesh's overall estimate and TriangleMesh::colors the
// per-vertex albedo divided by it (channel by channel; 0 where the overall is 0), so that the product that
// colours multiply into is the per-vertex albedo, while a renderer that ignores vertex colours still sees
// the mesh's mean. Drops the base colour texture, which would multiply the estimate again.
void applyAlbedo(Scene& scene, const AlbedoEstimate& estimate);

}  // namespace deltagi
DELTAGI_API_END
