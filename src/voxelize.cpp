#include "voxelize.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "parallel.h"

namespace deltagi {

bool triangleBoxOverlap(glm::vec3 boxCenter, glm::vec3 h, glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    const glm::vec3 v[3] = {a - boxCenter, b - boxCenter, c - boxCenter};
    // 1. The box's face normals: the triangle's bounds against the box.
    for (int i = 0; i < 3; ++i) {
        float mn = std::min({v[0][i], v[1][i], v[2][i]}), mx = std::max({v[0][i], v[1][i], v[2][i]});
        if (mn > h[i] || mx < -h[i]) return false;
    }
    // 2. The triangle's plane.
    const glm::vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
    glm::vec3 n = glm::cross(e[0], e[1]);
    float r = glm::dot(h, glm::abs(n));
    if (std::abs(glm::dot(n, v[0])) > r) return false;
    // 3. The nine cross products of box axes and triangle edges.
    for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < 3; ++i) {
            glm::vec3 axis(0.0f);
            axis[i] = 1.0f;
            glm::vec3 l = glm::cross(axis, e[k]);
            float p0 = glm::dot(l, v[0]), p1 = glm::dot(l, v[1]), p2 = glm::dot(l, v[2]);
            float rad = glm::dot(h, glm::abs(l));
            if (std::min({p0, p1, p2}) > rad || std::max({p0, p1, p2}) < -rad) return false;
        }
    }
    return true;
}

float clippedTriangleArea(glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 boxMin, glm::vec3 boxMax) {
    // A triangle clipped by 6 planes has at most 9 vertices.
    std::array<glm::vec3, 12> polyA{a, b, c}, polyB{};
    int count = 3;
    glm::vec3* in = polyA.data();
    glm::vec3* out = polyB.data();
    for (int plane = 0; plane < 6 && count > 0; ++plane) {
        const int axis = plane / 2;
        const bool keepAbove = plane % 2 == 0;  // keep p[axis] >= min, or p[axis] <= max
        const float bound = keepAbove ? boxMin[axis] : boxMax[axis];
        auto inside = [&](const glm::vec3& p) { return keepAbove ? p[axis] >= bound : p[axis] <= bound; };
        if (std::all_of(in, in + count, inside)) continue;  // the plane cuts nothing off (the usual case)
        int outCount = 0;
        for (int i = 0; i < count; ++i) {
            const glm::vec3& p = in[i];
            const glm::vec3& q = in[(i + 1) % count];
            const bool pIn = inside(p), qIn = inside(q);
            if (pIn) out[outCount++] = p;
            if (pIn != qIn) {
                float t = (bound - p[axis]) / (q[axis] - p[axis]);
                out[outCount++] = p + t * (q - p);
            }
        }
        count = outCount;
        std::swap(in, out);
    }
    glm::vec3 sum(0.0f);
    for (int i = 1; i + 1 < count; ++i) sum += glm::cross(in[i] - in[0], in[i + 1] - in[0]);
    return 0.5f * glm::length(sum);
}

namespace {

struct VoxelTriangle {
    VoxelTriangle() {}   // not zeroed: toVoxelSpace writes every one it reads
    glm::vec3 p[3];      // level-0 voxel coordinates
    glm::vec3 normal;    // unit face normal (winding order)
    float area;          // voxel units^2
    bool oneVoxel;       // lies inside a single voxel of the grid
    glm::vec3 emission;  // the material's emitted radiance
    glm::ivec3 lo, hi;   // voxel bounds, clamped to the grid; hi < lo: no voxel (degenerate or outside)
    bool touchesGrid() const { return hi.x >= lo.x; }
};

// Every triangle of `meshes` in voxel space, in mesh and triangle order; in parallel (a detailed object has
// many).
std::vector<VoxelTriangle, LargeBlockAllocator<VoxelTriangle>> toVoxelSpace(
    std::span<const TriangleMesh> meshes, const VolumeRegion& region) {
    constexpr size_t kChunk = 4096;
    struct Chunk {
        const TriangleMesh* mesh;
        size_t first, last, out;  // triangles [first, last) of mesh, written from `out` on
    };
    std::vector<Chunk> chunks;
    size_t total = 0;
    for (const TriangleMesh& mesh : meshes)
        for (size_t first = 0; first < mesh.triangles.size(); first += kChunk) {
            const size_t last = std::min(first + kChunk, mesh.triangles.size());
            chunks.push_back({&mesh, first, last, total});
            total += last - first;
        }
    std::vector<VoxelTriangle, LargeBlockAllocator<VoxelTriangle>> tris(total);
    const float invVoxel = 1.0f / region.voxelSize();
    const int n = region.resolution;
    parallelFor(0, static_cast<int64_t>(chunks.size()), 1, [&](int64_t c) {
        const Chunk& chunk = chunks[c];
        const TriangleMesh& mesh = *chunk.mesh;
        for (size_t i = chunk.first; i < chunk.last; ++i) {
            const glm::uvec3& t = mesh.triangles[i];
            VoxelTriangle& vt = tris[chunk.out + (i - chunk.first)];
            vt.lo = glm::ivec3(0);
            vt.hi = glm::ivec3(-1);
            for (int k = 0; k < 3; ++k) vt.p[k] = (mesh.positions[t[k]] - region.origin) * invVoxel;
            glm::vec3 cr = glm::cross(vt.p[1] - vt.p[0], vt.p[2] - vt.p[0]);
            float len = glm::length(cr);
            if (!(len > 0.0f)) continue;  // degenerate: covers no area
            vt.normal = cr / len;
            vt.area = 0.5f * len;
            vt.emission = mesh.material.emission;
            glm::vec3 mn = glm::min(vt.p[0], glm::min(vt.p[1], vt.p[2]));
            glm::vec3 mx = glm::max(vt.p[0], glm::max(vt.p[1], vt.p[2]));
            if (mx.x < 0 || mx.y < 0 || mx.z < 0 || mn.x > n || mn.y > n || mn.z > n) continue;
            vt.lo = glm::clamp(glm::ivec3(glm::floor(mn)), glm::ivec3(0), glm::ivec3(n - 1));
            vt.hi = glm::clamp(glm::ivec3(glm::floor(mx)), glm::ivec3(0), glm::ivec3(n - 1));
            vt.oneVoxel = glm::ivec3(glm::floor(mn)) == glm::ivec3(glm::floor(mx)) &&
                          glm::all(glm::greaterThanEqual(mn, glm::vec3(0.0f))) &&
                          glm::all(glm::lessThan(mx, glm::vec3(static_cast<float>(n))));
        }
    });
    return tris;
}

}  // namespace

VoxelGeometry voxelize(std::span<const TriangleMesh> meshes, const VolumeRegion& region) {
    const int n = region.resolution;
    VoxelGeometry out{Grid3(n), {}, {}, {}};
    out.area.assign(static_cast<size_t>(n) * n * n, 0.0f);
    revoxelize(out, meshes, region);
    return out;
}

VoxelBox revoxelize(VoxelGeometry& out, std::span<const TriangleMesh> meshes, const VolumeRegion& region) {
    const bool emissive =
        std::any_of(meshes.begin(), meshes.end(), [](const TriangleMesh& m) { return m.material.emits(); });
    // Clear the old geometry: the grid is zero everywhere then.
    const VoxelBox old = out.bounds;
    const bool hadEmission = !out.emission.empty();
    forEachRow(old, [&](int y, int z) {
        const size_t first = out.visibility.index(old.lo.x, y, z), count = old.hi.x - old.lo.x;
        std::fill_n(&out.visibility[first], count, glm::vec4(0.0f));
        std::fill_n(out.area.begin() + first, count, 0.0f);
        if (hadEmission) std::fill_n(out.emission.begin() + first, count, glm::vec3(0.0f));
    });
    if (!emissive) out.emission.clear();
    if (emissive && !hadEmission) out.emission.assign(out.area.size(), glm::vec3(0.0f));

    const auto tris = toVoxelSpace(meshes, region);
    VoxelBox& box = out.bounds;
    box = {};
    for (const VoxelTriangle& t : tris)
        if (t.touchesGrid()) box.extend({t.lo, t.hi + 1});
    if (box.empty()) return old;
    // Scatter in slabs of the box's layers.
    const int slabCount = (box.hi.z - box.lo.z + kSlabThickness - 1) / kSlabThickness;
    const SlabBins bins = binBySlab(tris.size(), slabCount, [&](size_t i) {
        if (!tris[i].touchesGrid()) return std::pair{1, 0};  // in no slab
        return std::pair{(tris[i].lo.z - box.lo.z) / kSlabThickness,
                         (tris[i].hi.z - box.lo.z) / kSlabThickness};
    });
    const glm::vec3 half(0.5f);
    parallelFor(0, slabCount, 1, [&](int64_t s) {
        const int zBegin = box.lo.z + static_cast<int>(s) * kSlabThickness;
        const int zEnd = std::min(zBegin + kSlabThickness, box.hi.z);
        for (uint32_t ti : bins.slab(s)) {
            const VoxelTriangle& t = tris[ti];
            for (int z = std::max(zBegin, t.lo.z); z < std::min(zEnd, t.hi.z + 1); ++z)
                for (int y = t.lo.y; y <= t.hi.y; ++y)
                    for (int x = t.lo.x; x <= t.hi.x; ++x) {
                        glm::vec3 boxMin(x, y, z);
                        // A triangle inside one voxel (most of a detailed mesh's) needs no test and no
                        // clipping.
                        const bool inside = t.oneVoxel;
                        if (!inside && !triangleBoxOverlap(boxMin + half, half, t.p[0], t.p[1], t.p[2]))
                            continue;
                        const float a =
                            inside ? t.area
                                   : clippedTriangleArea(t.p[0], t.p[1], t.p[2], boxMin, boxMin + 1.0f);
                        size_t i = out.visibility.index(x, y, z);
                        glm::vec4& v = out.visibility[i];
                        v.x = 1.0f;
                        v.y += t.normal.x * a;
                        v.z += t.normal.y * a;
                        v.w += t.normal.z * a;
                        out.area[i] += a;
                        if (emissive) out.emission[i] += t.emission * a;
                    }
        }
    });
    // Normal sums to area-weighted means; areas from voxel units to world units.
    const float voxelArea = region.voxelSize() * region.voxelSize();
    forEachRow(box, [&](int y, int z) {
        for (size_t i = out.visibility.index(box.lo.x, y, z), end = i + (box.hi.x - box.lo.x); i < end; ++i) {
            glm::vec4& v = out.visibility[i];
            float a = out.area[i];
            if (a > 0.0f) {
                v.y /= a;
                v.z /= a;
                v.w /= a;
            }
            out.area[i] = a * voxelArea;
            if (emissive) out.emission[i] *= voxelArea;
        }
    });
    return old;
}

}  // namespace deltagi
