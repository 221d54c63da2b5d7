#include "ray_scene.h"

#include <cstring>
#include <stdexcept>

#include <embree3/rtcore.h>

namespace deltagi {

struct RayScene::Impl {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
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

}  // namespace

RayScene::RayScene(const Scene& scene, SceneContent content, const RayScene* base)
    : impl_(std::make_unique<Impl>()), base_(base) {
    impl_->device = rtcNewDevice(nullptr);
    if (!impl_->device) throw std::runtime_error("Embree: cannot create a device");
    impl_->scene = rtcNewScene(impl_->device);
    // A layer of virtual objects is rebuilt every frame: a faster build for slightly slower rays.
    rtcSetSceneBuildQuality(impl_->scene, content == SceneContent::VirtualOnly ? RTC_BUILD_QUALITY_MEDIUM
                                                                               : RTC_BUILD_QUALITY_HIGH);
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
        rtcCommitGeometry(geom);
        unsigned id = rtcAttachGeometry(impl_->scene, geom);
        rtcReleaseGeometry(geom);
        if (id != meshes_.size()) throw std::logic_error("Embree geometry IDs are not consecutive");
        meshes_.push_back({&mesh, isVirtual});
        bounds_.extend(mesh.bounds());
    };
    if (content != SceneContent::VirtualOnly)
        for (const TriangleMesh& m : scene.real) add(m, false);
    if (content != SceneContent::RealOnly)
        for (const TriangleMesh& m : scene.virtuals) add(m, true);
    rtcCommitScene(impl_->scene);
}

RayScene::~RayScene() = default;

RayHit RayScene::intersect(glm::vec3 origin, glm::vec3 direction, float tMin, float tMax) const {
    RayHit hit = intersectTopLayer(origin, direction, tMin, tMax);
    if (base_) {
        RayHit below = base_->intersect(origin, direction, tMin, hit.hit() ? hit.t : tMax);
        if (below.hit()) hit = below;
    }
    return hit;
}

RayHit RayScene::intersectTopLayer(glm::vec3 origin, glm::vec3 direction, float tMin, float tMax) const {
    RayHit result;
    if (meshes_.empty()) return result;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    initRay(rh.ray, origin, direction, tMin, tMax);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->scene, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return result;

    const MeshRef& ref = meshes_[rh.hit.geomID];
    const TriangleMesh& mesh = *ref.mesh;
    const glm::uvec3 tri = mesh.triangles[rh.hit.primID];
    const float u = rh.hit.u, v = rh.hit.v;
    glm::vec3 n = (1.0f - u - v) * mesh.normals[tri.x] + u * mesh.normals[tri.y] + v * mesh.normals[tri.z];
    glm::vec3 ng(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    float len = glm::length(n);
    n = len > 0.0f ? n / len : glm::normalize(ng);
    // Two-sided: the shading normal faces the side the ray came from.
    if (glm::dot(ng, direction) > 0.0f) ng = -ng;
    if (glm::dot(n, ng) < 0.0f) n = -n;
    result.t = rh.ray.tfar;
    // Interpolate the position on the triangle (more precise than origin + t * direction far away).
    result.position =
        (1.0f - u - v) * mesh.positions[tri.x] + u * mesh.positions[tri.y] + v * mesh.positions[tri.z];
    result.normal = n;
    result.geometricNormal = glm::normalize(ng);
    result.material = &mesh.material;
    result.isVirtual = ref.isVirtual;
    return result;
}

}  // namespace deltagi
