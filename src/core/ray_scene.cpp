#include "core/ray_scene.h"

#include <cstring>
#include <deque>
#include <optional>
#include <stdexcept>

#include <embree3/rtcore.h>

namespace deltagi {

struct RayScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    // The alpha-masked meshes, for their geometries' filter functions (a deque: the addresses stay).
    std::deque<const TriangleMesh*> maskedMeshes;
    ~Impl() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

namespace {

void initRay(RTCRay& ray, glm::vec3 origin, glm::vec3 direction, float tMin, float tMax) {
    ray.org_x = origin.x;
    ray.org_y = origin.y;
    ray.org_z = origin.z;
    ray.dir_x = direction.x;
    ray.dir_y = direction.y;
    ray.dir_z = direction.z;
    ray.tnear = tMin;
    ray.tfar = tMax;
    ray.time = 0.0f;
    ray.mask = ~0u;
    ray.id = 0;
    ray.flags = 0;
}

// Lane k of a packet of 8 rays, as initRay for one.
void initPacketRay(RTCRay8& ray, size_t k, glm::vec3 origin, glm::vec3 direction, float tMax) {
    ray.org_x[k] = origin.x;
    ray.org_y[k] = origin.y;
    ray.org_z[k] = origin.z;
    ray.dir_x[k] = direction.x;
    ray.dir_y[k] = direction.y;
    ray.dir_z[k] = direction.z;
    ray.tnear[k] = 0.0f;
    ray.tfar[k] = tMax;
    ray.time[k] = 0.0f;
    ray.mask[k] = ~0u;
    ray.id[k] = static_cast<unsigned>(k);
    ray.flags[k] = 0;
}

// Packets of 8 of `count` rays: lane(packet, k, i) sets lane k to ray i and says whether it is traced (the
// lanes past the last ray repeat it, not traced), then trace(packet, valid, first, n) for rays [first, first
// + n).
constexpr size_t kPacket = 8;
template <typename Packet, typename Lane, typename Trace>
void forEachPacket(size_t count, Lane&& lane, Trace&& trace) {
    for (size_t first = 0; first < count; first += kPacket) {
        alignas(32) Packet packet;
        alignas(32) int valid[kPacket];
        const size_t n = std::min(kPacket, count - first);
        for (size_t k = 0; k < kPacket; ++k)
            valid[k] = lane(packet, k, first + std::min(k, n - 1)) && k < n ? -1 : 0;
        trace(packet, valid, first, n);
    }
}

// The context of a packet of rays from one point (or parallel), which Embree traces as coherent.
RTCIntersectContext coherentContext() {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    return context;
}

// The closest hit of one ray in `scene` into `rh`; false when it meets nothing.
bool closestHit(RTCScene scene, glm::vec3 origin, glm::vec3 direction, float tMin, float tMax,
                RTCRayHit& rh) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    initRay(rh.ray, origin, direction, tMin, tMax);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene, &context, &rh);
    return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

// The hit of a ray on the triangle Embree found, computed again from the mesh's vertices (Moller-Trumbore in
// double precision): the same bits whichever BVH found it, built afresh or refit. Embree's own figures
// depend, in the last bits, on how its leaves store the triangle.
// Virtual meshes only (about a quarter of the real G-buffer's time where it was done for every hit).
struct TriangleHit {
    float t, u, v;
    glm::vec3 ng;  // the triangle's plane normal (e1 x e2), not normalized
};
std::optional<TriangleHit> recomputeHit(glm::vec3 origin, glm::vec3 direction, glm::vec3 a, glm::vec3 b,
                                        glm::vec3 c) {
    const glm::dvec3 o(origin), d(direction), v0(a);
    const glm::dvec3 e1 = glm::dvec3(b) - v0, e2 = glm::dvec3(c) - v0;
    const glm::dvec3 p = glm::cross(d, e2);
    const double det = glm::dot(e1, p);
    if (det == 0.0) return std::nullopt;
    const double inv = 1.0 / det;
    const glm::dvec3 s = o - v0;
    const glm::dvec3 q = glm::cross(s, e1);
    return TriangleHit{static_cast<float>(glm::dot(e2, q) * inv), static_cast<float>(glm::dot(s, p) * inv),
                       static_cast<float>(glm::dot(d, q) * inv), glm::vec3(glm::cross(e1, e2))};
}

// Embree's filter for alpha-masked materials (glTF alphaMode MASK): a hit where the surface is cut away is
// no hit, for closest-hit and shadow rays alike.
void alphaMaskFilter(const RTCFilterFunctionNArguments* args) {
    const TriangleMesh& mesh = **static_cast<const TriangleMesh* const*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
        if (!surfacePresentAt(mesh, prim, RTCHitN_u(args->hit, args->N, i), RTCHitN_v(args->hit, args->N, i)))
            args->valid[i] = 0;
    }
}

// The mesh's normals interpolated at (u, v), unit length; `fallback` where they cancel.
glm::vec3 interpolatedNormal(const TriangleMesh& mesh, glm::uvec3 tri, float u, float v, glm::vec3 fallback) {
    const glm::vec3 n =
        (1.0f - u - v) * mesh.normals[tri.x] + u * mesh.normals[tri.y] + v * mesh.normals[tri.z];
    const float len = glm::length(n);
    return len > 0.0f ? n / len : fallback;
}

}  // namespace

RayScene::RayScene(const Scene& scene, SceneContent content, const RayScene* base)
    : impl_(std::make_unique<Impl>()), content_(content), base_(base) {
    impl_->device = rtcNewDevice(nullptr);
    if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
    impl_->scene = rtcNewScene(impl_->device);
    // A layer of virtual objects moves every frame: a faster build for slightly slower rays, and a two-level
    // structure (build quality low) whose meshes' BVHs can be refit (refit()).
    const bool dynamic = content == SceneContent::VirtualOnly;
    rtcSetSceneBuildQuality(impl_->scene, dynamic ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_HIGH);
    if (dynamic) rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_DYNAMIC);
    if (base) bounds_ = base->bounds();
    auto add = [&](const TriangleMesh& mesh, bool isVirtual) {
        if (mesh.triangles.empty()) return;
        RTCGeometry geom = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree-owned, padded buffers (Embree reads vertices with 16-byte loads).
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.positions.size()));
        std::memcpy(vertices, mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
        auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
            geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.triangles.size()));
        std::memcpy(indices, mesh.triangles.data(), mesh.triangles.size() * sizeof(glm::uvec3));
        if (dynamic) rtcSetGeometryBuildQuality(geom, RTC_BUILD_QUALITY_REFIT);
        if (mesh.material.alphaMode == AlphaMode::Mask) {
            impl_->maskedMeshes.push_back(&mesh);
            rtcSetGeometryUserData(geom, &impl_->maskedMeshes.back());
            rtcSetGeometryIntersectFilterFunction(geom, alphaMaskFilter);
            rtcSetGeometryOccludedFilterFunction(geom, alphaMaskFilter);
        }
        rtcCommitGeometry(geom);
        unsigned id = rtcAttachGeometry(impl_->scene, geom);
        rtcReleaseGeometry(geom);
        if (id != meshes_.size()) throw std::logic_error("Embree geometry IDs are not consecutive");
        meshes_.push_back({&mesh, isVirtual, vertices, indices, mesh.positions.size(), mesh.triangles.size(),
                           mesh.material.alphaMode == AlphaMode::Mask, variesOverSurface(mesh),
                           constantSurfaceMaterial(mesh.material)});
        bounds_.extend(mesh.bounds());
    };
    if (content != SceneContent::VirtualOnly)
        for (const TriangleMesh& m : scene.real) add(m, false);
    if (content != SceneContent::RealOnly)
        for (const TriangleMesh& m : scene.virtuals) add(m, true);
    rtcCommitScene(impl_->scene);
}

RayScene::~RayScene() = default;

bool RayScene::refit(const Scene& scene) {
    std::vector<const TriangleMesh*> meshes;
    auto collect = [&](const std::vector<TriangleMesh>& list) {
        for (const TriangleMesh& m : list)
            if (!m.triangles.empty()) meshes.push_back(&m);
    };
    if (content_ != SceneContent::VirtualOnly) collect(scene.real);
    if (content_ != SceneContent::RealOnly) collect(scene.virtuals);
    if (meshes.size() != meshes_.size()) return false;
    for (size_t g = 0; g < meshes.size(); ++g) {
        const TriangleMesh& now = *meshes[g];
        const MeshRef& built = meshes_[g];
        if (now.positions.size() != built.vertexCount || now.triangles.size() != built.triangleCount ||
            (now.material.alphaMode == AlphaMode::Mask) != built.masked ||
            std::memcmp(built.indices, now.triangles.data(), now.triangles.size() * sizeof(glm::uvec3)) != 0)
            return false;
    }
    bounds_ = base_ ? base_->bounds() : Bounds3f{};
    size_t masked = 0;
    for (size_t g = 0; g < meshes.size(); ++g) {
        if (meshes_[g].masked) impl_->maskedMeshes[masked++] = meshes[g];
        const TriangleMesh& mesh = *meshes[g];
        std::memcpy(meshes_[g].vertices, mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
        RTCGeometry geom = rtcGetGeometry(impl_->scene, static_cast<unsigned>(g));
        rtcUpdateGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(geom);
        meshes_[g].mesh = &mesh;
        meshes_[g].varying = variesOverSurface(mesh);
        meshes_[g].surface = constantSurfaceMaterial(mesh.material);
        bounds_.extend(mesh.bounds());
    }
    rtcCommitScene(impl_->scene);
    return true;
}

void RayScene::updateMaterials() {
    for (MeshRef& ref : meshes_) {
        ref.varying = variesOverSurface(*ref.mesh);
        ref.surface = constantSurfaceMaterial(ref.mesh->material);
    }
}

RayHit RayScene::intersect(glm::vec3 origin, glm::vec3 direction, float tMin, float tMax,
                           bool texturesLater) const {
    RayHit hit = intersectTopLayer(origin, direction, tMin, tMax, texturesLater);
    if (base_) {
        RayHit below = base_->intersect(origin, direction, tMin, hit.hit() ? hit.t : tMax, texturesLater);
        if (below.hit()) hit = below;
    }
    return hit;
}

RayHit RayScene::intersectTopLayer(glm::vec3 origin, glm::vec3 direction, float tMin, float tMax,
                                   bool texturesLater) const {
    RayHit result;
    RTCRayHit rh;
    if (meshes_.empty() || !closestHit(impl_->scene, origin, direction, tMin, tMax, rh)) return result;
    hitOn(rh.hit.geomID, rh.hit.primID, {rh.hit.u, rh.hit.v, rh.ray.tfar},
          {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z}, origin, direction, !texturesLater, result);
    return result;
}

RayLanding RayScene::land(glm::vec3 origin, glm::vec3 direction, float tMin, float tMax) const {
    RayLanding landing = landTopLayer(origin, direction, tMin, tMax);
    if (base_) {
        const RayLanding below = base_->land(origin, direction, tMin, landing.hit() ? landing.t : tMax);
        if (below.hit()) landing = below;
    }
    return landing;
}

RayLanding RayScene::landTopLayer(glm::vec3 origin, glm::vec3 direction, float tMin, float tMax) const {
    RayLanding landing;
    RTCRayHit rh;
    if (meshes_.empty() || !closestHit(impl_->scene, origin, direction, tMin, tMax, rh)) return landing;
    glm::vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    if (glm::dot(ng, direction) > 0.0f) ng = -ng;  // two-sided: facing the side the ray came from
    landing.t = rh.ray.tfar;
    landing.position = origin + rh.ray.tfar * direction;
    landing.geometricNormal = glm::normalize(ng);
    return landing;
}

void RayScene::intersectCoherent(glm::vec3 origin, std::span<const glm::vec3> directions,
                                 std::span<RayHit> hits, bool topLayerOnly, bool texturesLater) const {
    intersectCoherent(std::span(&origin, 1), directions, hits, topLayerOnly, texturesLater);
}

void RayScene::intersectCoherent(std::span<const glm::vec3> origins, std::span<const glm::vec3> directions,
                                 std::span<RayHit> hits, bool topLayerOnly, bool texturesLater) const {
    // One origin for all, or one per ray.
    auto originOf = [&](size_t i) { return origins.size() == 1 ? origins[0] : origins[i]; };
    if (meshes_.empty() || (base_ && !topLayerOnly)) {  // layers: one ray at a time
        for (size_t i = 0; i < directions.size(); ++i)
            hits[i] = topLayerOnly ? RayHit{}
                                   : intersect(originOf(i), directions[i], 0.0f,
                                               std::numeric_limits<float>::infinity(), texturesLater);
        return;
    }
    RTCIntersectContext context = coherentContext();
    forEachPacket<RTCRayHit8>(
        directions.size(),
        [&](RTCRayHit8& rh, size_t k, size_t i) {
            initPacketRay(rh.ray, k, originOf(i), directions[i], std::numeric_limits<float>::infinity());
            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
            return true;
        },
        [&](RTCRayHit8& rh, const int* valid, size_t first, size_t n) {
            rtcIntersect8(valid, impl_->scene, &context, &rh);
            for (size_t k = 0; k < n; ++k) {
                if (rh.hit.geomID[k] == RTC_INVALID_GEOMETRY_ID) {
                    hits[first + k] = RayHit{};
                    continue;
                }
                hitOn(rh.hit.geomID[k], rh.hit.primID[k], {rh.hit.u[k], rh.hit.v[k], rh.ray.tfar[k]},
                      {rh.hit.Ng_x[k], rh.hit.Ng_y[k], rh.hit.Ng_z[k]}, originOf(first + k),
                      directions[first + k], !texturesLater, hits[first + k]);
            }
        });
}

void RayScene::hitOn(unsigned geomID, unsigned primID, glm::vec3 uvt, glm::vec3 ng, glm::vec3 origin,
                     glm::vec3 direction, bool lookUpTextures, RayHit& result) const {
    const MeshRef& ref = meshes_[geomID];
    const TriangleMesh& mesh = *ref.mesh;
    const glm::uvec3 tri = mesh.triangles[primID];
    float u = uvt.x, v = uvt.y, t = uvt.z;
    // Only a virtual mesh's BVH is ever refit (a real one's is built once): its hits are computed again.
    if (const auto again = !ref.isVirtual ? std::nullopt
                                          : recomputeHit(origin, direction, mesh.positions[tri.x],
                                                         mesh.positions[tri.y], mesh.positions[tri.z])) {
        t = again->t, u = again->u, v = again->v, ng = again->ng;
    }
    result.t = t;
    // Interpolate the position on the triangle (more precise than origin + t * direction far away).
    result.position =
        (1.0f - u - v) * mesh.positions[tri.x] + u * mesh.positions[tri.y] + v * mesh.positions[tri.z];
    // Two-sided: the normals face the side the ray came from.
    if (glm::dot(ng, direction) > 0.0f) ng = -ng;
    result.geometricNormal = glm::normalize(ng);
    result.material = &mesh.material;
    result.mesh = &mesh;
    result.triangle = primID;
    result.barycentric = {u, v};
    const glm::vec3 n = interpolatedNormal(mesh, tri, u, v, result.geometricNormal);
    result.normalFlipped = glm::dot(n, result.geometricNormal) < 0.0f;
    result.normal = result.normalFlipped ? -n : n;
    result.surface = ref.surface;
    result.texturesLookedUp = false;
    result.isVirtual = ref.isVirtual;
    result.varies = ref.varying;
    if (ref.varying && lookUpTextures) lookUpMaterial(result, 0.0f);
}

void lookUpMaterial(RayHit& hit, float footprint) {
    const TriangleMesh& mesh = *hit.mesh;
    const float u = hit.barycentric.x, v = hit.barycentric.y;
    glm::vec3 n = !hit.texturesLookedUp
                      ? (hit.normalFlipped ? -hit.normal : hit.normal)
                      : interpolatedNormal(mesh, mesh.triangles[hit.triangle], u, v, hit.geometricNormal);
    hit.surface = surfaceMaterialAt(mesh, hit.triangle, u, v, footprint, &n);
    hit.normal = glm::dot(n, hit.geometricNormal) < 0.0f ? -n : n;
    hit.texturesLookedUp = true;
}

bool RayScene::occluded(glm::vec3 origin, glm::vec3 direction, float tMin, float tMax) const {
    return occludedTopLayer(origin, direction, tMin, tMax) ||
           (base_ && base_->occluded(origin, direction, tMin, tMax));
}

bool RayScene::occludedTopLayer(glm::vec3 origin, glm::vec3 direction, float tMin, float tMax) const {
    if (meshes_.empty()) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray;
    initRay(ray, origin, direction, tMin, tMax);
    rtcOccluded1(impl_->scene, &context, &ray);
    return ray.tfar < 0.0f;  // Embree sets tfar to -inf when the ray is occluded
}

void RayScene::occludedCoherent(glm::vec3 origin, std::span<const glm::vec3> directions,
                                std::span<const float> tMax, std::span<uint8_t> blocked) const {
    if (meshes_.empty()) {
        std::fill(blocked.begin(), blocked.end(), uint8_t{0});
        return;
    }
    RTCIntersectContext context = coherentContext();
    forEachPacket<RTCRay8>(
        directions.size(),
        [&](RTCRay8& ray, size_t k, size_t i) {
            initPacketRay(ray, k, origin, directions[i], tMax[i]);
            return tMax[i] > 0.0f;
        },
        [&](RTCRay8& ray, const int* valid, size_t first, size_t n) {
            rtcOccluded8(valid, impl_->scene, &context, &ray);
            for (size_t k = 0; k < n; ++k) blocked[first + k] = valid[k] && ray.tfar[k] < 0.0f ? 1 : 0;
        });
}

}  // namespace deltagi
