#include "pipeline/voxelize.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include <glm/ext/vector_int3_sized.hpp>

#include "core/parallel.h"
#include "core/surface_material.h"

namespace deltagi {

namespace {

// What the triangles of one mesh share: their material in the volumes.
struct VoxelMesh {
    glm::vec3 emission;  // the material's emitted radiance
    glm::vec3 albedo;    // what the material reflects into the volumes (Material::volumeReflectance)
    // Textured or vertex-coloured meshes: the mesh, whose material is looked up over each piece of a triangle
    // in a voxel instead (null: the constant emission and albedo above hold everywhere).
    const TriangleMesh* varying;
    // Its triangles' voxel materials when kept (VoxelGeometry::triangleMaterials), or null.
    const std::array<glm::vec3, 2>* cached;
};

// 76 bytes: 128 when each carried its mesh's material, which for the benchmark's 100k-triangle Buddha made
// voxelization 6.9 ms a frame instead of 6.2 (the records are written once and read three times).
struct VoxelTriangle {
    VoxelTriangle() {}  // not zeroed: toVoxelSpace writes every one it reads
    glm::vec3 p[3];     // level-0 voxel coordinates
    glm::vec3 normal;   // unit face normal (winding order)
    float area;         // voxel units^2
    uint32_t index;     // in its mesh
    uint32_t mesh;      // its VoxelMesh
    bool oneVoxel;      // lies inside a single voxel of the grid
    // Its voxel material is its mesh's kept one (VoxelMesh::cached[index]), for every piece of it: a triangle
    // smaller than a voxel is looked up once, at its centre, over a voxel's footprint (which covers it).
    bool cachedMaterial;
    // Voxel bounds, clamped to the grid (at most 1024 voxels a side); hi < lo: no voxel (degenerate or
    // outside).
    glm::i16vec3 lo, hi;
    bool touchesGrid() const { return hi.x >= lo.x; }
};
static_assert(sizeof(VoxelTriangle) <= 80);

// A convex polygon in voxel space: a triangle cut by voxel planes (at most 3 + 2 per axis vertices).
struct Polygon {
    std::array<glm::vec3, 12> v;
    int count = 0;
    void push(glm::vec3 p) { v[count++] = p; }
    float area() const {
        glm::vec3 sum(0.0f);
        for (int i = 1; i + 1 < count; ++i) sum += glm::cross(v[i] - v[0], v[i + 1] - v[0]);
        return 0.5f * glm::length(sum);
    }
    glm::vec3 vertexMean() const {
        glm::vec3 sum(0.0f);
        for (int i = 0; i < count; ++i) sum += v[i];
        return sum / static_cast<float>(count);
    }
};

// The parts of `p` on each side of the plane q[axis] = k, both closed (a vertex on the plane is in both; a
// polygon that only touches the plane leaves a part without area on that side). Either may be null.
void splitPolygon(const Polygon& p, int axis, float k, Polygon* below, Polygon* above) {
    if (below) below->count = 0;
    if (above) above->count = 0;
    for (int i = 0; i < p.count; ++i) {
        const glm::vec3 a = p.v[i], b = p.v[i + 1 < p.count ? i + 1 : 0];
        const float da = a[axis] - k, db = b[axis] - k;
        if (below && da <= 0.0f) below->push(a);
        if (above && da >= 0.0f) above->push(a);
        if ((da < 0.0f && db > 0.0f) || (da > 0.0f && db < 0.0f)) {
            glm::vec3 m = a + (da / (da - db)) * (b - a);
            m[axis] = k;  // exactly on the plane, for the next cuts
            if (below) below->push(m);
            if (above) above->push(m);
        }
    }
}

// Calls f(x, y, z, piece) for each voxel with lo <= (x, y) <= hi and z0 <= z < z1 that the triangle t touches
// (closed voxels), with the area of the part (a Polygon) of the triangle inside it: the triangle is cut into
// the voxels' pieces by the grid planes, one plane at a time. Layer by layer in z, row by row in y, then x.
template <typename F>
void forEachTouchedVoxel(const VoxelTriangle& t, int z0, int z1, F&& f) {
    Polygon triangle;
    for (const glm::vec3& p : t.p) triangle.push(p);
    const glm::vec3 mn = glm::min(t.p[0], glm::min(t.p[1], t.p[2]));
    const glm::vec3 mx = glm::max(t.p[0], glm::max(t.p[1], t.p[2]));
    // Calls each(i, part) with the part of `p` (a part of the triangle) in layer i of `axis`, for the layers
    // first <= i <= last that it touches. A plane that the triangle does not reach beyond is not cut at: the
    // cut would copy the polygon unchanged.
    auto layers = [&](const Polygon& p, int axis, int first, int last, auto&& each) {
        Polygon buffers[3];
        Polygon& part = buffers[2];
        const Polygon* rest = &p;
        if (mn[axis] < static_cast<float>(first)) {
            splitPolygon(p, axis, static_cast<float>(first), nullptr, &buffers[0]);
            rest = &buffers[0];
        }
        for (int i = first; i <= last && rest->count > 0; ++i) {
            if (i == last) {
                if (mx[axis] <= static_cast<float>(last + 1)) {
                    each(i, *rest);
                } else {
                    splitPolygon(*rest, axis, static_cast<float>(last + 1), &part, nullptr);
                    if (part.count > 0) each(i, part);
                }
                return;
            }
            Polygon& next = buffers[rest == &buffers[0] ? 1 : 0];
            splitPolygon(*rest, axis, static_cast<float>(i + 1), &part, &next);
            if (part.count > 0) each(i, part);
            rest = &next;
        }
    };
    // z from the slab's first layer z0 (slabs are cut each on its own), then y and x within each part.
    layers(triangle, 2, z0, z1 - 1, [&](int z, const Polygon& layerZ) {
        layers(layerZ, 1, t.lo.y, t.hi.y, [&](int y, const Polygon& rowY) {
            layers(rowY, 0, t.lo.x, t.hi.x, [&](int x, const Polygon& piece) { f(x, y, z, piece); });
        });
    });
}

// Embree's barycentric (u, v) of a point `p` in the plane of triangle t (p = (1 - u - v) p0 + u p1 + v p2).
glm::vec2 barycentricOf(const VoxelTriangle& t, glm::vec3 p) {
    const glm::vec3 e1 = t.p[1] - t.p[0], e2 = t.p[2] - t.p[0], d = p - t.p[0];
    const float d11 = glm::dot(e1, e1), d12 = glm::dot(e1, e2), d22 = glm::dot(e2, e2);
    const float d1 = glm::dot(d, e1), d2 = glm::dot(d, e2);
    const float det = d11 * d22 - d12 * d12;
    if (!(det > 0.0f)) return glm::vec2(1.0f / 3.0f);
    const glm::vec2 uv((d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det);
    return glm::clamp(uv, glm::vec2(0.0f), glm::vec2(1.0f));
}

// The steps of the voxel-material cache's scale: 1/64 octave, about 1 %. Quantized so that a turning object's
// scale, computed again from its rotated transform, gives the same key to the last bit.
constexpr float kScaleStepsPerOctave = 64.0f;

// A mesh's transform's scale (the cube root of its linear part's determinant), quantized.
float quantizedScale(const glm::mat4& worldFromObject) {
    const float scale = std::cbrt(std::abs(glm::determinant(glm::mat3(worldFromObject))));
    if (!(scale > 0.0f) || !std::isfinite(scale)) return 1.0f;
    return std::exp2(std::round(std::log2(scale) * kScaleStepsPerOctave) / kScaleStepsPerOctave);
}

// FNV-1a over what a mesh's triangle voxel materials depend on besides its object-space mesh.
uint64_t triangleMaterialSignature(const TriangleMesh& mesh, float voxelSize, float scale) {
    uint64_t hash = 0xcbf29ce484222325ull;
    auto bytes = [&](const void* data, size_t size) {
        for (size_t i = 0; i < size; ++i) {
            hash ^= static_cast<const unsigned char*>(data)[i];
            hash *= 0x100000001b3ull;
        }
    };
    auto value = [&](const auto& v) { bytes(&v, sizeof(v)); };
    value(voxelSize);
    value(scale);
    visitMaterialFields(mesh.material, value);
    return hash;
}

// Brings `cache` up to date for `meshes` (VoxelGeometry::triangleMaterials) and returns, per mesh, its
// triangles' kept voxel materials or null. A triangle's material is looked up on the object-space mesh's
// texture-coordinate density at the quantized scale, so that it does not depend on where the object is.
std::vector<const std::array<glm::vec3, 2>*> keptTriangleMaterials(
    std::span<const TriangleMesh> meshes, float voxelSize,
    std::vector<VoxelGeometry::TriangleMaterials>& cache) {
    cache.resize(meshes.size());
    std::vector<const std::array<glm::vec3, 2>*> kept(meshes.size(), nullptr);
    for (size_t k = 0; k < meshes.size(); ++k) {
        const TriangleMesh& mesh = meshes[k];
        VoxelGeometry::TriangleMaterials& entry = cache[k];
        const TriangleMesh* objectSpace = mesh.objectSpace.get();
        // Triangle i of the placed mesh is triangle i of the object-space one when clean-up dropped none (it
        // may drop unreferenced vertices: the indices differ then, the triangles' order does not).
        if (!objectSpace || !variesOverSurface(mesh) ||
            objectSpace->triangles.size() != mesh.triangles.size() ||
            objectSpace->uvs.size() != objectSpace->positions.size() ||
            mesh.uvs.size() != mesh.positions.size()) {
            entry = {};
            continue;
        }
        const float scale = quantizedScale(mesh.worldFromObject);
        const uint64_t signature = triangleMaterialSignature(mesh, voxelSize, scale);
        if (entry.objectSpace != objectSpace || entry.signature != signature ||
            entry.values.size() != mesh.triangles.size()) {
            entry.objectSpace = objectSpace;
            entry.signature = signature;
            entry.values.resize(mesh.triangles.size());
            const float objectFootprint = voxelSize / scale;
            parallelFor(0, static_cast<int64_t>(mesh.triangles.size()), 4096, [&](int64_t i) {
                const float uvFootprint = uvFootprintOn(objectSpace->positions, objectSpace->uvs,
                                                        objectSpace->triangles[i], objectFootprint);
                const SurfaceMaterial m = surfaceMaterialAtUv(mesh, static_cast<unsigned>(i), 1.0f / 3.0f,
                                                              1.0f / 3.0f, uvFootprint, nullptr);
                entry.values[i] = {m.emission, m.volumeReflectance()};
            });
        }
        kept[k] = entry.values.data();
    }
    return kept;
}

// Every triangle of `meshes` in voxel space, in mesh and triangle order, their meshes' shared part, and the
// voxels their bounding boxes touch; in parallel (a detailed object has many).
struct VoxelTriangles {
    std::vector<VoxelTriangle, LargeBlockAllocator<VoxelTriangle>> triangles;
    std::vector<VoxelMesh> meshes;
    VoxelBox bounds;
};

VoxelTriangles toVoxelSpace(std::span<const TriangleMesh> meshes, const VolumeRegion& region,
                            std::vector<VoxelGeometry::TriangleMaterials>& cache) {
    constexpr size_t kChunk = 4096;
    struct Chunk {
        uint32_t mesh;
        size_t first, last, out;  // triangles [first, last) of mesh, written from `out` on
        VoxelBox bounds;          // of its triangles' voxels
    };
    const std::vector<const std::array<glm::vec3, 2>*> kept =
        keptTriangleMaterials(meshes, region.voxelSize(), cache);
    VoxelTriangles result;
    std::vector<Chunk> chunks;
    size_t total = 0;
    for (size_t k = 0; k < meshes.size(); ++k) {
        const TriangleMesh& mesh = meshes[k];
        result.meshes.push_back({mesh.material.emission, mesh.material.volumeReflectance(),
                                 variesOverSurface(mesh) ? &mesh : nullptr, kept[k]});
        for (size_t first = 0; first < mesh.triangles.size(); first += kChunk) {
            const size_t last = std::min(first + kChunk, mesh.triangles.size());
            chunks.push_back({static_cast<uint32_t>(k), first, last, total, {}});
            total += last - first;
        }
    }
    auto& tris = result.triangles;
    tris.resize(total);
    const float invVoxel = 1.0f / region.voxelSize();
    const int n = region.resolution;
    parallelFor(0, static_cast<int64_t>(chunks.size()), 1, [&](int64_t c) {
        Chunk& chunk = chunks[c];
        const TriangleMesh& mesh = meshes[chunk.mesh];
        const bool cachedMesh = kept[chunk.mesh] != nullptr;
        for (size_t i = chunk.first; i < chunk.last; ++i) {
            const glm::uvec3& t = mesh.triangles[i];
            VoxelTriangle& vt = tris[chunk.out + (i - chunk.first)];
            vt.lo = glm::i16vec3(0);
            vt.hi = glm::i16vec3(-1);
            for (int k = 0; k < 3; ++k) vt.p[k] = (mesh.positions[t[k]] - region.origin) * invVoxel;
            glm::vec3 cr = glm::cross(vt.p[1] - vt.p[0], vt.p[2] - vt.p[0]);
            float len = glm::length(cr);
            if (!(len > 0.0f)) continue;  // degenerate: covers no area
            vt.normal = cr / len;
            vt.area = 0.5f * len;
            vt.index = static_cast<uint32_t>(i);
            vt.mesh = chunk.mesh;
            vt.cachedMaterial = false;
            glm::vec3 mn = glm::min(vt.p[0], glm::min(vt.p[1], vt.p[2]));
            glm::vec3 mx = glm::max(vt.p[0], glm::max(vt.p[1], vt.p[2]));
            if (mx.x < 0 || mx.y < 0 || mx.z < 0 || mn.x > n || mn.y > n || mn.z > n) continue;
            const glm::ivec3 lo = glm::clamp(glm::ivec3(glm::floor(mn)), glm::ivec3(0), glm::ivec3(n - 1));
            const glm::ivec3 hi = glm::clamp(glm::ivec3(glm::floor(mx)), glm::ivec3(0), glm::ivec3(n - 1));
            vt.lo = glm::i16vec3(lo);
            vt.hi = glm::i16vec3(hi);
            chunk.bounds.extend({lo, hi + 1});
            vt.cachedMaterial = cachedMesh && glm::all(glm::lessThanEqual(mx - mn, glm::vec3(1.0f)));
            vt.oneVoxel = glm::ivec3(glm::floor(mn)) == glm::ivec3(glm::floor(mx)) &&
                          glm::all(glm::greaterThanEqual(mn, glm::vec3(0.0f))) &&
                          glm::all(glm::lessThan(mx, glm::vec3(static_cast<float>(n))));
        }
    });
    for (const Chunk& chunk : chunks)
        if (!chunk.bounds.empty()) result.bounds.extend(chunk.bounds);
    return result;
}

// Empty arrays over `window` of an n^3 grid (emission is sized by revoxelize).
void allocateArrays(VoxelGeometry& out, int n, const VoxelBox& window) {
    out.visibility = Grid3(n, window);
    out.area.assign(out.visibility.size(), 0.0f);
    out.emission.clear();
}

// A slab's surface voxels (VoxelGeometry::surfaceVoxels' entries for its rows, in order), their albedo and
// each of its rows' count of them.
struct SlabSurfaces {
    std::vector<uint32_t> voxels;
    std::vector<glm::vec3> albedo;
    std::vector<uint32_t> rowCounts;  // per row (y, z) of the slab, z outer
};

}  // namespace

std::pair<uint32_t, uint32_t> surfaceVoxelsInRow(const VoxelGeometry& geometry, int y, int z, int x0) {
    const VoxelBox& box = geometry.bounds;
    if (geometry.surfaceRowStart.empty() || y < box.lo.y || y >= box.hi.y || z < box.lo.z || z >= box.hi.z)
        return {0, 0};
    const size_t row = static_cast<size_t>(z - box.lo.z) * (box.hi.y - box.lo.y) + (y - box.lo.y);
    const size_t n = static_cast<size_t>(geometry.visibility.resolution());
    const uint32_t first = (static_cast<uint32_t>(z) * n + static_cast<uint32_t>(y)) * n + std::max(x0, 0);
    const auto begin = geometry.surfaceVoxels.begin();
    const auto at = std::lower_bound(begin + geometry.surfaceRowStart[row],
                                     begin + geometry.surfaceRowStart[row + 1], first);
    return {static_cast<uint32_t>(at - begin), geometry.surfaceRowStart[row + 1]};
}

namespace {
VoxelBox voxelizeInto(VoxelGeometry& out, std::span<const TriangleMesh> meshes, const VolumeRegion& region,
                      bool withEmission);
}  // namespace

VoxelGeometry voxelize(std::span<const TriangleMesh> meshes, const VolumeRegion& region, bool withEmission,
                       bool withAlbedo, int windowMargin) {
    const int n = region.resolution;
    VoxelGeometry out;
    out.windowMargin = windowMargin;
    out.withAlbedo = withAlbedo;
    // With a margin, an empty window: voxelizeInto places it around the meshes.
    allocateArrays(out, n, windowMargin < 0 ? VoxelBox::all(n) : VoxelBox{});
    voxelizeInto(out, meshes, region, withEmission);
    return out;
}

VoxelGeometry voxelizePacked(std::span<const TriangleMesh> meshes, const VolumeRegion& region,
                             bool withEmission, bool withAlbedo) {
    const int n = region.resolution;
    VoxelGeometry out;
    out.withAlbedo = withAlbedo;
    out.packed = true;
    out.visibility = Grid3(n, VoxelBox{});  // no voxels: the grid's resolution
    out.area.assign(static_cast<size_t>(n) * n * n, 0.0f);
    out.packedVisibility = PackedGrid3(n);
    out.occupied.assign(out.area.size(), 0);
    voxelizeInto(out, meshes, region, withEmission);
    return out;
}

VoxelBox revoxelize(VoxelGeometry& out, std::span<const TriangleMesh> meshes, const VolumeRegion& region,
                    bool withEmission) {
    if (out.packed) throw std::logic_error("revoxelize: a packed voxelization is not redone in place");
    return voxelizeInto(out, meshes, region, withEmission);
}

namespace {

VoxelBox voxelizeInto(VoxelGeometry& out, std::span<const TriangleMesh> meshes, const VolumeRegion& region,
                      bool withEmission) {
    const bool packed = out.packed;
    const bool emissive =
        withEmission &&
        std::any_of(meshes.begin(), meshes.end(), [](const TriangleMesh& m) { return m.material.emits(); });
    const VoxelBox old = out.bounds;
    const bool withAlbedo = out.withAlbedo;
    const VoxelTriangles voxelTriangles = toVoxelSpace(meshes, region, out.triangleMaterials);
    const int n = region.resolution;
    if (out.windowMargin >= 0 && !out.visibility.window().contains(voxelTriangles.bounds)) {
        // The meshes left the window (or it is the first): empty arrays over a new one around them.
        const VoxelBox& b = voxelTriangles.bounds;
        allocateArrays(out, n, VoxelBox{b.lo - out.windowMargin, b.hi + out.windowMargin});
    } else {
        // Clear the old geometry: the grid is zero everywhere then.
        const bool hadEmission = !out.emission.empty();
        forEachRow(old, [&](int y, int z) {
            const size_t first = out.visibility.index(old.lo.x, y, z), count = old.hi.x - old.lo.x;
            std::fill_n(&out.visibility[first], count, glm::vec4(0.0f));
            std::fill_n(out.area.begin() + first, count, 0.0f);
            if (hadEmission) std::fill_n(out.emission.begin() + first, count, glm::vec3(0.0f));
        });
    }
    if (!emissive) out.emission.clear();
    if (emissive && out.emission.empty()) out.emission.assign(out.area.size(), glm::vec3(0.0f));

    const auto& tris = voxelTriangles.triangles;
    VoxelBox& box = out.bounds;
    box = voxelTriangles.bounds;
    out.surfaceVoxels.clear();
    out.surfaceRowStart.clear();
    out.albedo.clear();
    if (box.empty()) return old;
    // Scatter in slabs of the box's layers; each slab then finishes its voxels and lists its surface voxels
    // (a voxel gets pieces from its own slab's task alone).
    const int slabCount = (box.hi.z - box.lo.z + kSlabThickness - 1) / kSlabThickness;
    const glm::ivec3 extent = box.hi - box.lo;
    const size_t layerVoxels = static_cast<size_t>(extent.x) * extent.y;
    std::vector<SlabSurfaces> surfaces(withAlbedo ? slabCount : 0);
    const float voxelArea = region.voxelSize() * region.voxelSize();
    const SlabBins bins = binBySlab(tris.size(), slabCount, [&](size_t i) {
        if (!tris[i].touchesGrid()) return std::pair{1, 0};  // in no slab
        return std::pair{(tris[i].lo.z - box.lo.z) / kSlabThickness,
                         (tris[i].hi.z - box.lo.z) / kSlabThickness};
    });
    // The arrays' index of a voxel inside the box (a packed geometry's `visibility` stores none).
    auto arrayIndex = [&](int x, int y, int z) {
        return packed ? out.indexOf(x, y, z) : out.visibility.index(x, y, z);
    };
    parallelFor(0, slabCount, 1, [&](int64_t s) {
        const int zBegin = box.lo.z + static_cast<int>(s) * kSlabThickness;
        const int zEnd = std::min(zBegin + kSlabThickness, box.hi.z);
        // The slab's albedo sums and (packed) its visibility sums, over the box's rows of its layers (a
        // thread's buffers, zero between slabs).
        thread_local std::vector<glm::vec3> albedoSums;
        thread_local std::vector<glm::vec4> visibilitySums;
        if (withAlbedo && albedoSums.size() < layerVoxels * kSlabThickness)
            albedoSums.assign(layerVoxels * kSlabThickness, glm::vec3(0.0f));
        if (packed && visibilitySums.size() < layerVoxels * kSlabThickness)
            visibilitySums.assign(layerVoxels * kSlabThickness, glm::vec4(0.0f));
        auto inSlab = [&](int x, int y, int z) {
            return static_cast<size_t>(z - zBegin) * layerVoxels +
                   static_cast<size_t>(y - box.lo.y) * extent.x + static_cast<size_t>(x - box.lo.x);
        };
        auto albedoAt = [&](int x, int y, int z) -> glm::vec3& { return albedoSums[inSlab(x, y, z)]; };
        auto visibilityAt = [&](int x, int y, int z, size_t i) -> glm::vec4& {
            return packed ? visibilitySums[inSlab(x, y, z)] : out.visibility[i];
        };
        // The emission and albedo of a textured triangle's piece `where` (voxel space): its material at the
        // piece's centre, its textures filtered over a voxel (the voxel averages all its pieces anyway; a
        // piece's own, smaller footprint reads finer mip levels, for nothing but cache misses).
        auto materialOf = [&](const VoxelTriangle& t, const VoxelMesh& mesh, glm::vec3 where) {
            const glm::vec2 uv = barycentricOf(t, where);
            const SurfaceMaterial m =
                surfaceMaterialAt(*mesh.varying, t.index, uv.x, uv.y, region.voxelSize(), nullptr);
            return std::pair{m.emission, m.volumeReflectance()};
        };
        auto add = [&](int x, int y, int z, const VoxelTriangle& t, float a, glm::vec3 where) {
            const VoxelMesh& mesh = voxelTriangles.meshes[t.mesh];
            const size_t i = arrayIndex(x, y, z);
            glm::vec4& v = visibilityAt(x, y, z, i);
            v.x = 1.0f;
            v.y += t.normal.x * a;
            v.z += t.normal.y * a;
            v.w += t.normal.z * a;
            out.area[i] += a;
            if (mesh.varying && (emissive || withAlbedo)) {
                const auto [emission, albedo] =
                    t.cachedMaterial ? std::pair{mesh.cached[t.index][0], mesh.cached[t.index][1]}
                                     : materialOf(t, mesh, where);
                if (emissive) out.emission[i] += emission * a;
                if (withAlbedo) albedoAt(x, y, z) += albedo * a;
                return;
            }
            if (emissive) out.emission[i] += mesh.emission * a;
            if (withAlbedo) albedoAt(x, y, z) += mesh.albedo * a;
        };
        for (uint32_t ti : bins.slab(s)) {
            const VoxelTriangle& t = tris[ti];
            // A triangle inside one voxel (most of a detailed mesh's) needs no cutting.
            if (t.oneVoxel) {
                add(t.lo.x, t.lo.y, t.lo.z, t, t.area, (t.p[0] + t.p[1] + t.p[2]) / 3.0f);
                continue;
            }
            forEachTouchedVoxel(t, std::max(zBegin, static_cast<int>(t.lo.z)), std::min(zEnd, t.hi.z + 1),
                                [&](int x, int y, int z, const Polygon& piece) {
                                    add(x, y, z, t, piece.area(),
                                        voxelTriangles.meshes[t.mesh].varying && !t.cachedMaterial
                                            ? piece.vertexMean()
                                            : glm::vec3(0.0f));
                                });
        }
        // Normal sums to area-weighted means, areas from voxel units to world units; with albedo, the slab's
        // surface voxels (occupancy 1) listed row by row with their mean albedo, the sums cleared.
        SlabSurfaces* list = withAlbedo ? &surfaces[s] : nullptr;
        const size_t n = static_cast<size_t>(region.resolution);
        for (int z = zBegin; z < zEnd; ++z)
            for (int y = box.lo.y; y < box.hi.y; ++y) {
                const size_t first = arrayIndex(box.lo.x, y, z);
                const uint32_t firstInGrid = static_cast<uint32_t>(
                    (static_cast<size_t>(z) * n + static_cast<size_t>(y)) * n + box.lo.x);
                uint32_t count = 0;
                for (int x = box.lo.x; x < box.hi.x; ++x) {
                    const size_t i = first + (x - box.lo.x);
                    glm::vec4& v = visibilityAt(x, y, z, i);
                    // Only an occupied voxel got pieces: every sum is zero elsewhere, and stays so.
                    if (!(v.x > 0.0f)) continue;
                    const float a = out.area[i];
                    if (a > 0.0f) {
                        v.y /= a;
                        v.z /= a;
                        v.w /= a;
                    }
                    out.area[i] = a * voxelArea;
                    if (emissive) out.emission[i] *= voxelArea;
                    if (packed) {
                        out.packedVisibility.set(x, y, z, v);
                        out.occupied[i] = 1;
                        v = glm::vec4(0.0f);
                    }
                    if (!list) continue;
                    glm::vec3& sum = albedoAt(x, y, z);
                    list->voxels.push_back(firstInGrid + static_cast<uint32_t>(x - box.lo.x));
                    list->albedo.push_back(a > 0.0f ? sum / a : sum);
                    ++count;
                    sum = glm::vec3(0.0f);
                }
                if (list) list->rowCounts.push_back(count);
            }
    });
    if (!withAlbedo) return old;
    // The slabs' lists, in slab order: the rows' order (z outer, then y), each row's voxels by x.
    out.surfaceRowStart.assign(1, 0);
    out.surfaceRowStart.reserve(static_cast<size_t>(extent.y) * extent.z + 1);
    for (const SlabSurfaces& slab : surfaces) {
        out.surfaceVoxels.insert(out.surfaceVoxels.end(), slab.voxels.begin(), slab.voxels.end());
        out.albedo.insert(out.albedo.end(), slab.albedo.begin(), slab.albedo.end());
        for (uint32_t count : slab.rowCounts)
            out.surfaceRowStart.push_back(out.surfaceRowStart.back() + count);
    }
    return old;
}

}  // namespace

}  // namespace deltagi
