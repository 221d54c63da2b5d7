// Voxel volumes: a cubic grid of 4-float voxels with its mip chain (§3.1, Fig. 1).
//
// All four volumes of the method share this layout and the region of §3.4:
//   visibility volume: (occlusion, occlusion * average normal)  -- premultiplied, so a mip level is the plain
//                      mean of its 8 children: occlusion becomes the fraction of filled sub-voxels (§3.2) and
//                      the normal the occlusion-weighted mean normal, whose length says how coherent it is;
//   light volume:      (occlusion * radiance rgb, occlusion)     -- premultiplied the same way.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include <glm/glm.hpp>

#include "deltagi/renderer.h"

namespace deltagi {

// One level: n^3 voxels, x fastest. Move-only: volumes are large.
class Grid3 {
public:
    Grid3() = default;
    explicit Grid3(int n) : n_(n), voxels_(static_cast<size_t>(n) * n * n, glm::vec4(0.0f)) {}
    Grid3(Grid3&&) noexcept = default;
    Grid3& operator=(Grid3&&) noexcept = default;
    Grid3(const Grid3&) = delete;
    Grid3& operator=(const Grid3&) = delete;

    int resolution() const { return n_; }
    size_t size() const { return voxels_.size(); }
    size_t index(int x, int y, int z) const { return (static_cast<size_t>(z) * n_ + y) * n_ + x; }
    glm::vec4& at(int x, int y, int z) { return voxels_[index(x, y, z)]; }
    const glm::vec4& at(int x, int y, int z) const { return voxels_[index(x, y, z)]; }
    glm::vec4& operator[](size_t i) { return voxels_[i]; }
    const glm::vec4& operator[](size_t i) const { return voxels_[i]; }
    // Zero outside the grid (clamp-to-border).
    glm::vec4 fetch(int x, int y, int z) const {
        if (static_cast<unsigned>(x) >= static_cast<unsigned>(n_) ||
            static_cast<unsigned>(y) >= static_cast<unsigned>(n_) ||
            static_cast<unsigned>(z) >= static_cast<unsigned>(n_))
            return glm::vec4(0.0f);
        return voxels_[index(x, y, z)];
    }

private:
    int n_ = 0;
    std::vector<glm::vec4> voxels_;
};

// A level-0 grid and its mip chain over a region. Level l has resolution n / 2^l; its voxels are 2^l level-0
// voxels wide.
class MipVolume {
public:
    MipVolume() = default;
    MipVolume(VolumeRegion region, std::vector<Grid3> levels) : region_(region), levels_(std::move(levels)) {}

    const VolumeRegion& region() const { return region_; }
    int levelCount() const { return static_cast<int>(levels_.size()); }
    const Grid3& level(int l) const { return levels_[l]; }
    bool empty() const { return levels_.empty(); }

    // Trilinear sample of level `l` at `voxelPos` in level-0 voxel units (0 at the region's corner).
    glm::vec4 sampleLevel(glm::vec3 voxelPos, int l) const {
        const float scale = 1.0f / static_cast<float>(1 << l);
        glm::vec3 q = voxelPos * scale - 0.5f;
        glm::vec3 base = glm::floor(q);
        glm::vec3 f = q - base;
        int x = static_cast<int>(base.x), y = static_cast<int>(base.y), z = static_cast<int>(base.z);
        const Grid3& g = levels_[l];
        glm::vec4 c00 = glm::mix(g.fetch(x, y, z), g.fetch(x + 1, y, z), f.x);
        glm::vec4 c10 = glm::mix(g.fetch(x, y + 1, z), g.fetch(x + 1, y + 1, z), f.x);
        glm::vec4 c01 = glm::mix(g.fetch(x, y, z + 1), g.fetch(x + 1, y, z + 1), f.x);
        glm::vec4 c11 = glm::mix(g.fetch(x, y + 1, z + 1), g.fetch(x + 1, y + 1, z + 1), f.x);
        return glm::mix(glm::mix(c00, c10, f.y), glm::mix(c01, c11, f.y), f.z);
    }
    // Quadrilinear sample: trilinear in the two levels around the fractional `level`, blended.
    glm::vec4 sample(glm::vec3 voxelPos, float level) const {
        level = glm::clamp(level, 0.0f, static_cast<float>(levelCount() - 1));
        int l0 = static_cast<int>(level);
        float t = level - static_cast<float>(l0);
        glm::vec4 a = sampleLevel(voxelPos, l0);
        if (t <= 0.0f || l0 + 1 >= levelCount()) return a;
        return glm::mix(a, sampleLevel(voxelPos, l0 + 1), t);
    }

private:
    VolumeRegion region_;
    std::vector<Grid3> levels_;
};

}  // namespace deltagi
