#include "pipeline/inject.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <tuple>

#include "core/parallel.h"

namespace deltagi {

namespace {
// One light's texels in one voxel: their reflected flux, footprint area and number.
struct TexelSum {
    glm::vec3 flux{0.0f};
    float area = 0.0f;
    float count = 0.0f;
    void add(const RsmTexel& t) {
        flux += t.flux;
        area += t.area;
        count += 1.0f;
    }
};

// Where a voxel is in a geometry's arrays (VoxelGeometry::indexOf), by its index in the whole grid, or by
// that and its coordinates.
struct AtGridIndex {
    size_t voxel;
    size_t operator()(const VoxelGeometry& g) const { return g.indexOf(voxel); }
};
struct AtVoxel {
    size_t voxel;
    int x, y, z;
    size_t operator()(const VoxelGeometry& g) const { return g.whole() ? voxel : g.indexOf(x, y, z); }
};

// The surface area of `geometry` in a voxel (world units^2).
template <typename At>
[[gnu::always_inline]] inline float geometryArea(std::span<const VoxelGeometry* const> geometry, At at) {
    float area = 0.0f;
    for (const VoxelGeometry* g : geometry)
        if (const size_t j = at(*g); j != VoxelGeometry::kOutside) area += g->area[j];
    return area;
}

// lightRadiance's blend: the footprint share as it is (up to kSparseMaxFraction) with up to kSparseAcross
// texels across a voxel, full from kDenseFullShare of it with kDenseAcross and more.
constexpr float kSparseAcross = 3.0f, kDenseAcross = 6.0f;  // texels across a voxel
constexpr float kDenseFullShare = 0.75f, kSparseMaxFraction = 4.0f;

// The radiance one light's texels give a voxel from their sum and the geometry's `area` in it: the mean
// radiance of the lit texels (reflected flux / (pi * footprint area)), times the lit fraction of the voxel's
// surface, footprint / area. Footprints tile a lit surface only up to the map's sampling: with k texels
// across the voxel's surface, a fully lit voxel collects between about (k-1)^2 and (k+1)^2 of its k^2. Where
// the map is dense (k >= 6) a voxel whose footprints cover 3/4 of its area counts as fully lit, which removes
// that aliasing; where it is sparse the footprint share is kept as it is (up to 4: a grazing texel's
// footprint reaches into the voxels beside), as any threshold would darken the voxels that caught fewer
// texels than the mean more than it brightens the others. Between, the two blend. Each light's is computed
// apart and the lights' are summed: a voxel lit fully by two lights has the radiance of both, not their mean.
[[gnu::always_inline]] inline glm::vec3 lightRadiance(const TexelSum& sum, float area) {
    if (!(sum.area > 0.0f)) return glm::vec3(0.0f);
    float litFraction = 1.0f;
    if (area > 0.0f) {
        const float share = sum.area / area;
        const float across = std::sqrt(sum.count / share);  // k: the texels across the voxel's surface
        const float dense = std::clamp((across - kSparseAcross) / (kDenseAcross - kSparseAcross), 0.0f, 1.0f);
        const float fullShare = 1.0f - (1.0f - kDenseFullShare) * dense;
        const float maxFraction = kSparseMaxFraction - (kSparseMaxFraction - 1.0f) * dense;
        litFraction = std::min(maxFraction, share / fullShare);
    }
    return sum.flux * (litFraction / (std::numbers::pi_v<float> * sum.area));
}

// The texels of one voxel as they arrive in light and texel order: each light's sum is turned into its
// radiance (lightRadiance) when the next light's texels start, and the lights' radiances are summed in light
// order. injectLight and reinjectLight add the same numbers in the same order.
struct VoxelTexels {
    float area = 0.0f;         // of the geometry in the voxel
    glm::vec3 radiance{0.0f};  // of the lights finished
    TexelSum current;          // the current light's
    uint32_t light = 0;
    bool lit = false;  // any texel at all
    void add(uint32_t l, const RsmTexel& t) {
        if (lit && l != light) finishLight();
        light = l;
        lit = true;
        current.add(t);
    }
    void finishLight() {
        radiance += lightRadiance(current, area);
        current = TexelSum{};
    }
};

// A voxel of the light volume from its texels' radiance (`lit`: any texel landed in it) and the geometry in
// it.
template <typename At>
[[gnu::always_inline]] inline glm::vec4 voxelLight(glm::vec3 reflected, bool lit,
                                                   std::span<const VoxelGeometry* const> geometry, At at) {
    float occupancy = 0.0f, area = 0.0f;
    glm::vec3 emitted(0.0f);  // radiance times area
    for (const VoxelGeometry* g : geometry) {
        const size_t j = at(*g);
        if (j == VoxelGeometry::kOutside) continue;
        occupancy = std::max(occupancy, g->occupancy(j));
        area += g->area[j];
        if (!g->emission.empty()) emitted += g->emission[j];
    }
    glm::vec3 radiance(0.0f);
    if (lit) {
        occupancy = 1.0f;
        radiance = reflected;
    }
    // Emissive surfaces add their own radiance, averaged over all the surface area in the voxel.
    if (area > 0.0f && emitted != glm::vec3(0.0f)) radiance += emitted / area;
    return glm::vec4(radiance * occupancy, occupancy);
}

[[gnu::always_inline]] inline glm::vec4 deltaVoxel(glm::vec4 full, glm::vec4 sceneOnly) {
    return glm::vec4(full.x - sceneOnly.x, full.y - sceneOnly.y, full.z - sceneOnly.z, full.w);
}

// Whether voxel i (of the whole grid) is on a surface of `geometry` (VoxelGeometry::surfaceVoxels).
[[gnu::always_inline]] inline bool onASurface(std::span<const VoxelGeometry* const> geometry, size_t i) {
    for (const VoxelGeometry* g : geometry)
        if (const size_t j = g->indexOf(i); j != VoxelGeometry::kOutside && g->occupancy(j) > 0.0f)
            return true;
    return false;
}

// Whether each of `geometry` lists its surface voxels (voxelize's `withAlbedo`).
bool surfacesListed(std::span<const VoxelGeometry* const> geometry) {
    return std::all_of(geometry.begin(), geometry.end(), [](const VoxelGeometry* g) {
        return g->bounds.empty() || !g->surfaceRowStart.empty();
    });
}

// injectLight's grid of n^3 voxels, all zero: `recycled`'s, zeroed where it wrote, when it has the size and
// its voxels are listed; else a new one.
Grid3 zeroGrid(int n, std::span<const VoxelGeometry* const> geometry, bool listed, RecycledGrid* recycled) {
    if (!recycled || !listed || !recycled->written.listed || recycled->grid.resolution() != n ||
        !recycled->grid.whole())
        return Grid3(n);
    Grid3 grid = std::move(recycled->grid);
    forEachListedVoxel(geometry, recycled->written, [&](size_t i) { grid[i] = glm::vec4(0.0f); });
    return grid;
}

}  // namespace

Grid3 injectLight(std::span<const ReflectiveShadowMap> rsms, const VolumeRegion& region,
                  std::span<const VoxelGeometry* const> geometry, InjectedVoxels* written,
                  RecycledGrid* recycled) {
    if (written) *written = InjectedVoxels{};
    const int n = region.resolution;
    // voxelLight is zero where no texel landed and no surface is: with the surface voxels listed, only they
    // and the lit voxels off them (a texel rounded into the voxel beside its surface) are visited.
    const bool listed = surfacesListed(geometry);

    // Per voxel: the lights' summed radiance, and (w) 1 where any texel landed; then the light volume, in
    // place.
    Grid3 light = zeroGrid(n, geometry, listed, recycled);
    const TexelVoxels texelVoxel(region);
    const int slabCount = (n + kSlabThickness - 1) / kSlabThickness;
    const size_t slabVoxels = static_cast<size_t>(kSlabThickness) * n * n;
    std::vector<uint32_t> voxels;
    std::vector<std::vector<uint32_t>> offSurfaces(listed ? slabCount : 0);  // lit voxels, by slab
    for (const ReflectiveShadowMap& rsm : rsms) {
        // Each texel's voxel: the map's own where it holds them for this region.
        std::span<const uint32_t> voxelOf = rsm.voxelsIn(region);
        if (voxelOf.size() != rsm.texels.size()) {
            voxels.resize(rsm.texels.size());
            parallelFor(0, static_cast<int64_t>(voxels.size()), 1 << 14,
                        [&](int64_t t) { voxels[t] = texelVoxel.index(rsm.texels[t].position); });
            voxelOf = voxels;
        }
        const SlabBins bins = binBySlab(voxelOf.size(), slabCount, [&](size_t t) {
            const int s = static_cast<int>(voxelOf[t] / (static_cast<size_t>(n) * n)) / kSlabThickness;
            return std::pair{s, s};
        });
        parallelFor(0, slabCount, 1, [&](int64_t s) {
            // One light's texels of the slab: (reflected flux, footprint area) per voxel, then their
            // radiance. A thread's slab of sums, all zero between slabs.
            thread_local std::vector<TexelSum> accum;
            if (accum.size() != slabVoxels) accum.assign(slabVoxels, TexelSum{});
            const size_t first = static_cast<size_t>(s) * slabVoxels;
            for (uint32_t t : bins.slab(s)) accum[voxelOf[t] - first].add(rsm.texels[t]);
            // Each voxel of the slab once (at its first texel), in the slab's order.
            for (uint32_t t : bins.slab(s)) {
                TexelSum& sum = accum[voxelOf[t] - first];
                if (sum.area > 0.0f) {
                    const uint32_t v = voxelOf[t];
                    light[v] += glm::vec4(lightRadiance(sum, geometryArea(geometry, AtGridIndex{v})), 0.0f);
                    if (listed && light[v].w == 0.0f && !onASurface(geometry, v)) offSurfaces[s].push_back(v);
                    light[v].w = 1.0f;
                }
                sum = TexelSum{};
            }
        });
    }

    auto finish = [&](size_t i) {
        light[i] = voxelLight(glm::vec3(light[i]), light[i].w > 0.0f, geometry, AtGridIndex{i});
    };
    if (!listed) {
        forEachRow(VoxelBox::all(n), [&](int y, int z) {
            for (int x = 0; x < n; ++x) {
                const size_t i = light.index(x, y, z);
                light[i] = voxelLight(glm::vec3(light[i]), light[i].w > 0.0f, geometry, AtVoxel{i, x, y, z});
            }
        });
        return light;
    }
    // Each surface voxel once: the first geometry's, then each next one's off the ones before.
    for (size_t g = 0; g < geometry.size(); ++g)
        forEachSurfaceVoxel(*geometry[g], [&](size_t, size_t, size_t i) {
            if (!onASurface(geometry.first(g), i)) finish(i);
        });
    parallelFor(0, slabCount, 1, [&](int64_t s) {
        for (uint32_t i : offSurfaces[s]) finish(i);
    });
    if (written) {
        written->listed = true;
        for (const std::vector<uint32_t>& slab : offSurfaces)
            written->offSurface.insert(written->offSurface.end(), slab.begin(), slab.end());
    }
    return light;
}

PackedGrid3 packInjected(const Grid3& grid, std::span<const VoxelGeometry* const> geometry,
                         const InjectedVoxels& written) {
    if (!written.listed || !grid.whole()) return PackedGrid3(grid);
    return packListed(grid.resolution(), geometry, written, [&](size_t i) { return grid[i]; });
}

namespace {

template <typename Grid, typename NonZero>
std::optional<VoxelBox> boundsOfListed(const Grid& grid, std::span<const VoxelGeometry* const> geometry,
                                       const InjectedVoxels& written, NonZero&& nonZero) {
    if (!written.listed || !grid.whole()) return std::nullopt;
    const size_t n = static_cast<size_t>(grid.resolution());
    auto box = [n](size_t i) {
        return VoxelBox::voxel(
            glm::ivec3(static_cast<int>(i % n), static_cast<int>(i / n % n), static_cast<int>(i / (n * n))));
    };
    // Each row of surface voxels its own box (one task per row), joined after: min and max, the same in any
    // order.
    VoxelBox bounds;
    for (const VoxelGeometry* g : geometry) {
        const size_t rows = g->surfaceRowStart.empty() ? 0 : g->surfaceRowStart.size() - 1;
        std::vector<VoxelBox> rowBounds(rows);
        forEachSurfaceVoxel(*g, [&](size_t row, size_t, size_t i) {
            if (nonZero(i)) rowBounds[row].extend(box(i));
        });
        for (const VoxelBox& b : rowBounds) bounds.extend(b);
    }
    for (const uint32_t i : written.offSurface)
        if (nonZero(i)) bounds.extend(box(i));
    return bounds;
}

}  // namespace

std::optional<VoxelBox> injectedBounds(const Grid3& grid, std::span<const VoxelGeometry* const> geometry,
                                       const InjectedVoxels& written) {
    return boundsOfListed(grid, geometry, written, [&](size_t i) { return grid[i] != glm::vec4(0.0f); });
}

std::optional<VoxelBox> injectedBounds(const PackedGrid3& grid,
                                       std::span<const VoxelGeometry* const> geometry,
                                       const InjectedVoxels& written) {
    return boundsOfListed(grid, geometry, written, [&](size_t i) { return !zeroVoxel(grid, i); });
}

PackedGrid3 deltaVolume(const Grid3& full, const Grid3& sceneOnly) {
    return PackedGrid3::fromEach(full.resolution(),
                                 [&](size_t i) { return deltaVoxel(full[i], sceneOnly[i]); });
}

VoxelRows::VoxelRows(int resolution)
    : n_(resolution),
      lo_(static_cast<size_t>(resolution) * resolution, static_cast<uint16_t>(resolution)),
      hi_(static_cast<size_t>(resolution) * resolution, 0) {}

VoxelRows VoxelRows::all(int resolution) {
    VoxelRows rows(resolution);
    rows.add(VoxelBox::all(resolution));
    return rows;
}

void VoxelRows::add(const VoxelBox& box) {
    if (box.empty()) return;
    for (int z = box.lo.z; z < box.hi.z; ++z)
        for (int y = box.lo.y; y < box.hi.y; ++y) {
            const size_t r = static_cast<size_t>(z) * n_ + y;
            lo_[r] = std::min(lo_[r], static_cast<uint16_t>(box.lo.x));
            hi_[r] = std::max(hi_[r], static_cast<uint16_t>(box.hi.x));
        }
}

void VoxelRows::add(int x, int y, int z) {
    add(VoxelBox::voxel(glm::ivec3(x, y, z)));
}

void VoxelRows::add(const VoxelRows& other) {
    for (size_t r = 0; r < lo_.size(); ++r)
        if (other.lo_[r] < other.hi_[r]) {
            lo_[r] = std::min(lo_[r], other.lo_[r]);
            hi_[r] = std::max(hi_[r], other.hi_[r]);
        }
}

bool VoxelRows::contains(const VoxelRows& other) const {
    for (size_t r = 0; r < lo_.size(); ++r)
        if (other.lo_[r] < other.hi_[r] && (other.lo_[r] < lo_[r] || other.hi_[r] > hi_[r])) return false;
    return true;
}

size_t VoxelRows::count() const {
    size_t sum = 0;
    for (size_t r = 0; r < lo_.size(); ++r)
        if (lo_[r] < hi_[r]) sum += hi_[r] - lo_[r];
    return sum;
}

VoxelBox VoxelRows::bounds() const {
    VoxelBox box;
    for (size_t r = 0; r < lo_.size(); ++r)
        if (lo_[r] < hi_[r]) {
            const int y = static_cast<int>(r % n_), z = static_cast<int>(r / n_);
            box.extend({glm::ivec3(lo_[r], y, z), glm::ivec3(hi_[r], y + 1, z + 1)});
        }
    return box;
}

TexelBins binTexels(std::span<const ReflectiveShadowMap> rsms, const VolumeRegion& region,
                    const VoxelRows& voxels) {
    const int n = region.resolution;
    TexelBins bins;
    bins.resolution = n;
    bins.voxels = voxels;
    // A counting sort by row, which keeps injectLight's order inside each row, then each row by x.
    const TexelVoxels texelVoxel(region);
    size_t texels = 0;
    for (const ReflectiveShadowMap& rsm : rsms) texels += rsm.texels.size();
    // Each texel's voxel, found in parallel: the row (z * n + y) and x; kOutside for a voxel not binned.
    constexpr uint32_t kOutside = std::numeric_limits<uint32_t>::max();
    std::vector<uint32_t> rowOf(texels);
    std::vector<uint16_t> xOf(texels);
    size_t first = 0;
    const uint32_t un = static_cast<uint32_t>(n);
    for (const ReflectiveShadowMap& rsm : rsms) {
        // The map's voxels where it holds them (a few bytes a texel, not its position's).
        const std::span<const uint32_t> known = rsm.voxelsIn(region);
        const bool held = known.size() == rsm.texels.size();
        parallelFor(0, static_cast<int64_t>(rsm.texels.size()), 1 << 14, [&](int64_t t) {
            const glm::ivec3 v = held ? glm::ivec3(known[t] % un, known[t] / un % un, known[t] / (un * un))
                                      : texelVoxel(rsm.texels[t].position);
            rowOf[first + t] =
                voxels.contains(v.x, v.y, v.z) ? static_cast<uint32_t>(v.z * n + v.y) : kOutside;
            xOf[first + t] = static_cast<uint16_t>(v.x);
        });
        first += rsm.texels.size();
    }
    bins.rowStart.assign(static_cast<size_t>(n) * n + 1, 0);
    for (uint32_t row : rowOf)
        if (row != kOutside) ++bins.rowStart[row + 1];
    for (size_t r = 0; r + 1 < bins.rowStart.size(); ++r) bins.rowStart[r + 1] += bins.rowStart[r];
    bins.entries.resize(bins.rowStart.back());
    std::vector<uint32_t> cursor(bins.rowStart.begin(), bins.rowStart.end() - 1);
    size_t k = 0;
    for (size_t l = 0; l < rsms.size(); ++l)
        for (size_t t = 0; t < rsms[l].texels.size(); ++t, ++k)
            if (rowOf[k] != kOutside)
                bins.entries[cursor[rowOf[k]]++] = {xOf[k], static_cast<uint16_t>(l),
                                                    static_cast<uint32_t>(t)};
    parallelFor(0, static_cast<int64_t>(n) * n, 64, [&](int64_t r) {
        std::stable_sort(bins.entries.begin() + bins.rowStart[r], bins.entries.begin() + bins.rowStart[r + 1],
                         [](const TexelBins::Entry& a, const TexelBins::Entry& b) { return a.x < b.x; });
    });
    return bins;
}

RsmChanges compareRsms(std::span<const ReflectiveShadowMap> sceneAlone, std::span<const RsmUpdate> updates,
                       const VolumeRegion& region) {
    // Texels are compared as bytes: a copy is the same bytes.
    static_assert(sizeof(RsmTexel) == 11 * sizeof(float), "RsmTexel has padding");
    const int n = region.resolution;
    const TexelVoxels texelVoxel(region);
    auto voxelIndex = [&](const RsmTexel& t) { return texelVoxel.index(t.position); };
    // One piece of work per range, in light and texel order.
    struct Piece {
        uint32_t light;
        TexelRange range;
        std::vector<RsmChanges::Texel> removed, added;
    };
    std::vector<Piece> pieces;
    for (size_t l = 0; l < updates.size(); ++l)
        for (const TexelRange& r : updates[l].retraced)
            pieces.push_back({static_cast<uint32_t>(l), r, {}, {}});
    auto byIndex = [](const RsmTexel& t, uint32_t index) { return t.index < index; };
    parallelFor(0, static_cast<int64_t>(pieces.size()), 1, [&](int64_t p) {
        Piece& piece = pieces[p];
        const RsmTexels& before = sceneAlone[piece.light].texels;
        const RsmTexels& after = updates[piece.light].texels;
        auto b = std::lower_bound(before.begin(), before.end(), piece.range.first, byIndex);
        auto a = std::lower_bound(after.begin(), after.end(), piece.range.first, byIndex);
        auto removed = [&](RsmTexels::const_iterator t) {
            piece.removed.push_back(
                {voxelIndex(*t), piece.light, &*t, static_cast<uint32_t>(t - before.begin())});
        };
        auto added = [&](RsmTexels::const_iterator t) {
            piece.added.push_back(
                {voxelIndex(*t), piece.light, &*t, static_cast<uint32_t>(t - after.begin())});
        };
        const uint32_t last = piece.range.last;
        while (true) {
            const bool bIn = b != before.end() && b->index < last, aIn = a != after.end() && a->index < last;
            if (!bIn && !aIn) break;
            if (bIn && aIn && b->index == a->index) {
                if (std::memcmp(&*b, &*a, sizeof(RsmTexel)) != 0) {
                    removed(b);
                    added(a);
                }
                ++b, ++a;
            } else if (bIn && (!aIn || b->index < a->index)) {
                removed(b++);
            } else {
                added(a++);
            }
        }
    });
    RsmChanges changes;
    for (Piece& piece : pieces) {
        changes.removed.insert(changes.removed.end(), piece.removed.begin(), piece.removed.end());
        changes.added.insert(changes.added.end(), piece.added.begin(), piece.added.end());
    }
    std::sort(changes.added.begin(), changes.added.end(), [](const auto& a, const auto& b) {
        return std::tuple(a.voxel, a.light, a.texel->index) < std::tuple(b.voxel, b.light, b.texel->index);
    });
    changes.voxels = VoxelRows(n);
    for (const auto* list : {&changes.removed, &changes.added})
        for (const RsmChanges::Texel& t : *list)
            changes.voxels.add(static_cast<int>(t.voxel % n), static_cast<int>(t.voxel / n % n),
                               static_cast<int>(t.voxel / n / n));
    return changes;
}

namespace {

// The scene's texels that the objects removed or changed, as positions in `bins.entries` (increasing).
std::vector<uint32_t> goneEntries(const TexelBins& bins, const RsmChanges& changes) {
    const uint32_t n = static_cast<uint32_t>(bins.resolution);
    std::vector<uint32_t> gone;
    gone.reserve(changes.removed.size());
    for (const RsmChanges::Texel& t : changes.removed) {
        const uint32_t row = t.voxel / n, x = t.voxel % n;
        const auto rowEnd = bins.entries.begin() + bins.rowStart[row + 1];
        auto e = std::lower_bound(bins.entries.begin() + bins.rowStart[row], rowEnd, x,
                                  [](const TexelBins::Entry& e, uint32_t x) { return e.x < x; });
        while (e != rowEnd && (e->light != t.light || e->texel != t.position)) ++e;  // its voxel's few
        assert(e != rowEnd && e->x == x);  // every texel of the scene's maps is binned
        if (e != rowEnd) gone.push_back(static_cast<uint32_t>(e - bins.entries.begin()));
    }
    std::sort(gone.begin(), gone.end());
    return gone;
}

// Per voxel x0 <= x < x1 of row (y, z), its texels with the objects (VoxelTexels, finished): the scene's
// texels that are not gone and the added ones, merged into injectLight's order (map, then texel) so that the
// sums add the same numbers in the same order, and round the same.
std::vector<VoxelTexels> rowTexelSums(int y, int z, int x0, int x1, const TexelBins& bins,
                                      std::span<const ReflectiveShadowMap> sceneAlone,
                                      std::span<const uint32_t> gone, const RsmChanges& changes,
                                      std::span<const VoxelGeometry* const> geometry) {
    const int n = bins.resolution;
    const size_t row = static_cast<size_t>(z) * n + y;
    const uint32_t rowVoxel = static_cast<uint32_t>(row * n);  // the index of voxel (0, y, z)
    const std::vector<TexelBins::Entry>& entries = bins.entries;
    auto e = std::lower_bound(entries.begin() + bins.rowStart[row], entries.begin() + bins.rowStart[row + 1],
                              x0, [](const TexelBins::Entry& e, int x) { return e.x < x; });
    const auto eEnd = entries.begin() + bins.rowStart[row + 1];
    auto g = std::lower_bound(gone.begin(), gone.end(), static_cast<uint32_t>(e - entries.begin()));
    auto a = std::lower_bound(changes.added.begin(), changes.added.end(), rowVoxel + x0,
                              [](const RsmChanges::Texel& t, uint32_t v) { return t.voxel < v; });
    std::vector<VoxelTexels> sums(x1 - x0);
    for (int x = x0; x < x1; ++x)
        sums[x - x0].area = geometryArea(geometry, AtVoxel{rowVoxel + static_cast<size_t>(x), x, y, z});
    while (true) {
        const bool eIn = e != eEnd && e->x < x1;
        const bool aIn = a != changes.added.end() && a->voxel < rowVoxel + x1;
        if (!eIn && !aIn) break;
        const RsmTexel* sceneTexel = eIn ? &sceneAlone[e->light].texels[e->texel] : nullptr;
        if (eIn && (!aIn || std::tuple(rowVoxel + e->x, uint32_t{e->light}, sceneTexel->index) <
                                std::tuple(a->voxel, a->light, a->texel->index))) {
            if (g != gone.end() && *g == static_cast<uint32_t>(e - entries.begin()))
                ++g;  // removed or changed by the objects
            else
                sums[e->x - x0].add(e->light, *sceneTexel);
            ++e;
        } else {
            sums[a->voxel - rowVoxel - x0].add(a->light, *a->texel);
            ++a;
        }
    }
    for (VoxelTexels& texels : sums)
        if (texels.lit) texels.finishLight();
    return sums;
}

}  // namespace

void reinjectLight(const VoxelRows& voxels, const TexelBins& sceneTexels,
                   std::span<const ReflectiveShadowMap> sceneAlone, const RsmChanges& changes,
                   std::span<const VoxelGeometry* const> geometry, const Grid3& sceneLight,
                   PackedGrid3& fullLight, PackedGrid3& deltaLight, const SurfaceRadiance* bounce) {
    const std::vector<uint32_t> gone = goneEntries(sceneTexels, changes);
    voxels.forEachRow([&](int y, int z, int x0, int x1) {
        const std::vector<VoxelTexels> sums =
            rowTexelSums(y, z, x0, x1, sceneTexels, sceneAlone, gone, changes, geometry);
        // The row's surface voxels of geometry[0], walked along with x for the bounce.
        auto [k, kEnd] =
            bounce ? surfaceVoxelsInRow(*geometry[0], y, z, x0) : std::pair<uint32_t, uint32_t>{};
        for (int x = x0; x < x1; ++x) {
            const size_t i = fullLight.index(x, y, z);
            const VoxelTexels& texels = sums[x - x0];
            glm::vec4 light = voxelLight(texels.radiance, texels.lit, geometry, AtVoxel{i, x, y, z});
            if (bounce) {
                // Zero off the surface voxels, added all the same: the bits of adding a grid's zero.
                glm::vec3 b(0.0f);
                if (k < kEnd && geometry[0]->surfaceVoxels[k] == i) b = (*bounce)[k++];
                light += glm::vec4(b, 0.0f);
            }
            fullLight.set(i, light);
            deltaLight.set(i, deltaVoxel(light, sceneLight[i]));
        }
    });
}

}  // namespace deltagi
