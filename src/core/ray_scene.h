// Ray casting against the scene with Embree 3: the camera's G-buffer and the reflective shadow maps are
// rendered by casting one ray per sample instead of rasterizing. Embree types stay inside ray_scene.cpp.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <span>

#include <glm/glm.hpp>

#include "core/surface_material.h"
#include "deltagi/math.h"
#include "deltagi/scene.h"

namespace deltagi {

// Shadow and bounce rays start this fraction of the scene's extent off the surface, so that a surface does
// not shadow itself through floating-point error.
constexpr float kRayOffsetScale = 1e-4f;

struct RayHit {
    float t = std::numeric_limits<float>::infinity();  // distance along the (unit) ray direction
    glm::vec3 position{0.0f};
    glm::vec3 normal{
        0.0f};  // interpolated shading normal, unit, facing the ray's origin (two-sided surfaces)
    glm::vec3 geometricNormal{0.0f};  // the triangle's plane normal, unit, facing the ray's origin
    const Material* material = nullptr;
    SurfaceMaterial surface;  // the material at the hit, textures looked up at their finest level
    // Where the hit is: the mesh, its triangle and the barycentric weights (u, v) of the triangle's second
    // and third vertices (the first's is 1 - u - v): for textures and per-vertex quantities.
    const TriangleMesh* mesh = nullptr;
    unsigned triangle = 0;
    glm::vec2 barycentric{0.0f};
    bool isVirtual = false;
    bool varies = false;  // its mesh's material varies over the surface (variesOverSurface)
    // Whether `normal` is the mesh's interpolated normal turned round to face the ray, and whether the
    // material's textures were looked up (normal then normal-mapped): lookUpMaterial() starts from the
    // unmapped normal without interpolating it again.
    bool normalFlipped = false;
    bool texturesLookedUp = false;
    bool hit() const { return material != nullptr; }
};

// Where a ray lands, and no more: for rays that only read a volume there (no normals interpolated, no
// materials, no textures).
struct RayLanding {
    float t = std::numeric_limits<float>::infinity();
    glm::vec3 position{0.0f};         // origin + t * direction
    glm::vec3 geometricNormal{0.0f};  // the triangle's plane normal, unit, facing the ray's origin
    bool hit() const { return t < std::numeric_limits<float>::infinity(); }
};

// Looks up the material of a hit again for a lookup `footprint` world units wide (a camera pixel's), so
// that textures are filtered over it (their mip level); sets `hit.surface` and, for normal-mapped
// materials, `hit.normal`. Nothing changes for materials without textures.
void lookUpMaterial(RayHit& hit, float footprint);

// Which meshes a RayScene holds.
enum class SceneContent { RealOnly, RealAndVirtual, VirtualOnly };

// Owns an Embree device and scene (RAII). Holds pointers into `scene`'s meshes: the Scene must outlive it.
//
// A RayScene may be layered over a `base` RayScene (which must outlive it): queries then answer for both, so
// that the virtual objects, which move every frame, get their own small BVH over the reconstruction's, which
// is built once (FrameRenderer).
class RayScene {
  public:
    RayScene(const Scene& scene, SceneContent content, const RayScene* base = nullptr);
    ~RayScene();
    RayScene(const RayScene&) = delete;
    RayScene& operator=(const RayScene&) = delete;

    // Moves this layer to `scene`'s meshes (its content, as at construction) when they have the same
    // triangles as the meshes it was built over, only other vertex positions and normals: the BVH is refit
    // instead of built again (objects that move from frame to frame). False, and nothing changed, when the
    // triangles differ. `scene` must outlive the layer from then on.
    bool refit(const Scene& scene);
    // Reads this layer's meshes' materials and vertex colours again, after they changed (the geometry must
    // not have): hits give the new ones. Hits use a copy of each untextured material's values made at
    // construction (and by refit()), so that they need not compute them again and again.
    void updateMaterials();

    // Closest hit along origin + t * direction (direction unit length), t in (tMin, tMax). `texturesLater`
    // as for intersectCoherent().
    RayHit intersect(glm::vec3 origin, glm::vec3 direction, float tMin = 0.0f,
                     float tMax = std::numeric_limits<float>::infinity(), bool texturesLater = false) const;
    // The closest hit in this layer alone, without the base's.
    RayHit intersectTopLayer(glm::vec3 origin, glm::vec3 direction, float tMin = 0.0f,
                             float tMax = std::numeric_limits<float>::infinity(),
                             bool texturesLater = false) const;
    // intersect() and intersectTopLayer() for rays that need only where they land.
    RayLanding land(glm::vec3 origin, glm::vec3 direction, float tMin = 0.0f,
                    float tMax = std::numeric_limits<float>::infinity()) const;
    RayLanding landTopLayer(glm::vec3 origin, glm::vec3 direction, float tMin = 0.0f,
                            float tMax = std::numeric_limits<float>::infinity()) const;
    // intersect() (or intersectTopLayer()) for many rays from one origin (camera rays), traced in packets:
    // hits[i] for directions[i] (unit length), t in (0, infinity). The same hits as one ray at a time: each
    // is computed again from its triangle (an edge shared by two triangles may be found on either, at the
    // same point to rounding). `texturesLater`: the caller looks the materials of textured meshes up
    // itself (lookUpMaterial() with its footprint), so hits on them come with the material's factors and the
    // unmapped normal instead of a lookup at the finest texels.
    void intersectCoherent(glm::vec3 origin, std::span<const glm::vec3> directions, std::span<RayHit> hits,
                           bool topLayerOnly = false, bool texturesLater = false) const;
    // The same for rays of their own origins (origins[i], e.g. a directional light's parallel rays).
    void intersectCoherent(std::span<const glm::vec3> origins, std::span<const glm::vec3> directions,
                           std::span<RayHit> hits, bool topLayerOnly = false,
                           bool texturesLater = false) const;
    // Whether anything lies along origin + t * direction, t in (tMin, tMax): shadow rays (any hit, cheaper
    // than the closest). Of this layer and its base, or of this layer alone.
    bool occluded(glm::vec3 origin, glm::vec3 direction, float tMin = 0.0f,
                  float tMax = std::numeric_limits<float>::infinity()) const;
    bool occludedTopLayer(glm::vec3 origin, glm::vec3 direction, float tMin = 0.0f,
                          float tMax = std::numeric_limits<float>::infinity()) const;
    // occludedTopLayer() for many rays from one origin (camera rays), t in (0, tMax[i]), traced in packets:
    // blocked[i] for directions[i]; a ray with tMax[i] <= 0 is not traced (not blocked).
    void occludedCoherent(glm::vec3 origin, std::span<const glm::vec3> directions,
                          std::span<const float> tMax, std::span<uint8_t> blocked) const;
    const RayScene* base() const { return base_; }
    Bounds3f bounds() const { return bounds_; }  // of this layer and its base
    bool empty() const { return meshes_.empty() && (!base_ || base_->empty()); }

  private:
    // The hit on triangle `primID` of mesh `geomID` that Embree found at (u, v, t) with normal `ng`.
    // Writes every field of `out` (a caller's buffer: no 120-byte record made and copied per hit).
    void hitOn(unsigned geomID, unsigned primID, glm::vec3 uvt, glm::vec3 ng, glm::vec3 origin,
               glm::vec3 direction, bool lookUpTextures, RayHit& out) const;
    struct Impl;
    std::unique_ptr<Impl> impl_;
    struct MeshRef {
        const TriangleMesh* mesh;
        bool isVirtual;
        float* vertices;  // Embree's buffers, of vertexCount vertices and triangleCount triangles
        const unsigned* indices;
        size_t vertexCount, triangleCount;
        bool masked;              // an alpha-masked material: Embree filters its hits
        bool varying;             // variesOverSurface(): each hit looks its material up
        SurfaceMaterial surface;  // else this, everywhere
    };
    SceneContent content_;

    std::vector<MeshRef> meshes_;  // indexed by Embree geometry ID
    const RayScene* base_ = nullptr;
    Bounds3f bounds_;
};

}  // namespace deltagi
