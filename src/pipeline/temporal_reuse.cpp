#include "pipeline/temporal_reuse.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

#include "core/parallel.h"

namespace deltagi {

namespace {

// A kept frame's pixel shows the same surface when its depth is within this fraction of the reprojected one.
constexpr float kDepthTolerance = 0.02f;
// Bilinear weights below this in all (the accepted pixels' share) count as no history.
constexpr float kMinWeight = 1e-3f;

// Where a world point lands in a camera's image: pixel-centre coordinates (pixel (i, j)'s centre is (i, j))
// and its depth along the camera's axis; false behind the camera.
class Projector {
  public:
    explicit Projector(const Camera& camera)
        : camera_(&camera), cameraFromWorld_(glm::inverse(camera.worldFromCamera)) {}
    bool project(glm::vec3 p, glm::vec2& pixel, float& depth) const {
        const glm::vec3 q = glm::vec3(cameraFromWorld_ * glm::vec4(p, 1.0f));
        if (!(q.z < -1e-6f)) return false;
        depth = -q.z;
        pixel = camera_->imagePoint(q) - glm::vec2(0.5f);
        return std::isfinite(pixel.x) && std::isfinite(pixel.y);
    }
    float depth(glm::vec3 p) const { return -(cameraFromWorld_ * glm::vec4(p, 1.0f)).z; }

  private:
    const Camera* camera_;
    glm::mat4 cameraFromWorld_;
};

struct Taps {
    std::array<size_t, 4> index{};
    std::array<float, 4> weight{};
    int count = 0;
};

// The bilinear taps around `pixel` (pixel-centre coordinates) that `accept(x, y)` takes (x, y in the image),
// their weights normalized; none when their share is below kMinWeight.
template <typename Accept>
Taps bilinearTaps(glm::vec2 pixel, int width, int height, Accept&& accept) {
    Taps taps;
    if (!(pixel.x > -1.0f && pixel.y > -1.0f && pixel.x < static_cast<float>(width) &&
          pixel.y < static_cast<float>(height)))
        return taps;
    const float fx = std::floor(pixel.x), fy = std::floor(pixel.y);
    const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
    const float ax = pixel.x - fx, ay = pixel.y - fy;
    float total = 0.0f;
    for (int dy = 0; dy <= 1; ++dy)
        for (int dx = 0; dx <= 1; ++dx) {
            const int x = x0 + dx, y = y0 + dy;
            if (x < 0 || y < 0 || x >= width || y >= height) continue;
            const float w = (dx ? ax : 1.0f - ax) * (dy ? ay : 1.0f - ay);
            if (w <= 0.0f || !accept(x, y)) continue;
            taps.index[taps.count] = static_cast<size_t>(y) * width + x;
            taps.weight[taps.count++] = w;
            total += w;
        }
    if (total < kMinWeight) {
        taps.count = 0;
        return taps;
    }
    for (int k = 0; k < taps.count; ++k) taps.weight[k] /= total;
    return taps;
}

glm::vec3 fetch(const Taps& taps, const std::vector<glm::vec3>& values) {
    glm::vec3 sum(0.0f);
    for (int k = 0; k < taps.count; ++k) sum += taps.weight[k] * values[taps.index[k]];
    return sum;
}

bool closeDepth(float kept, float depth) {
    return kept >= 0.0f && std::abs(kept - depth) <= kDepthTolerance * depth;
}

// The range of `values` over the 3 x 3 pixels around (x, y) that `same(j)` takes (the centre always does).
struct Range {
    glm::vec3 lo, hi;
    bool flat() const { return lo == hi; }
    glm::vec3 clamp(glm::vec3 v) const { return glm::clamp(v, lo, hi); }
};
template <typename Same>
Range neighbourhood(const std::vector<glm::vec3>& values, size_t centre, int x, int y, int width, int height,
                    Same&& same) {
    Range r{values[centre], values[centre]};
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= width || yy >= height) continue;
            const size_t j = static_cast<size_t>(yy) * width + xx;
            if (!same(j)) continue;
            r.lo = glm::min(r.lo, values[j]);
            r.hi = glm::max(r.hi, values[j]);
        }
    return r;
}

// A pixel's mean over the window: this frame's value and the kept ones, each clamped to `range`, summed as
// differences from this frame's (where they agree, the mean is this frame's value exactly).
class WindowMean {
  public:
    WindowMean(glm::vec3 now, const Range& range) : now_(now), range_(range) {}
    void add(glm::vec3 kept) {
        sum_ += range_.clamp(kept) - now_;
        n_ += 1.0f;
    }
    glm::vec3 mean() const { return now_ + sum_ / n_; }
    bool averaged() const { return n_ > 1.0f; }

  private:
    glm::vec3 now_, sum_{0.0f};
    Range range_;
    float n_ = 1.0f;
};

// The one tap of a point that stayed at its pixel.
Taps samePixel(size_t index) {
    Taps taps;
    taps.index[0] = index;
    taps.weight[0] = 1.0f;
    taps.count = 1;
    return taps;
}

// How an object's vertices moved from a kept frame to this one.
struct ObjectMotion {
    enum class Kind { Still, Shifted, Deformed, Changed };
    Kind kind = Kind::Changed;  // Changed: another mesh (vertex count), nothing to follow
    glm::vec3 shift{0.0f};      // Shifted: now - then, the same for every vertex (to float rounding)
};
ObjectMotion motionOf(const std::vector<glm::vec3>& then, const std::vector<glm::vec3>& now,
                      bool sameCamera) {
    ObjectMotion m;
    if (then.size() != now.size() || now.empty()) return m;
    if (sameCamera && then == now) {
        m.kind = ObjectMotion::Kind::Still;
        return m;
    }
    // One shift for all (the rounding of adding it to each vertex aside): the points need no vertex then.
    const glm::vec3 shift = now[0] - then[0];
    for (size_t v = 0; v < now.size(); ++v) {
        const glm::vec3 error = glm::abs(now[v] - then[v] - shift);
        const glm::vec3 a = glm::abs(now[v]);
        const float scale = 1e-5f * (1.0f + std::max({a.x, a.y, a.z}));
        if (error.x > scale || error.y > scale || error.z > scale) {
            m.kind = ObjectMotion::Kind::Deformed;
            return m;
        }
    }
    m.kind = ObjectMotion::Kind::Shifted;
    m.shift = shift;
    return m;
}

// This frame's own values and surfaces, into `f` (its memory reused).
void record(const TemporalSurfaces& s, const TemporalValues& v, TemporalReuse::Frame& f) {
    const Camera& camera = *s.camera;
    const int width = camera.width, height = camera.height;
    const size_t count = static_cast<size_t>(width) * height;
    f.camera = camera;
    f.width = width;
    f.height = height;
    f.realDepth.resize(count);
    f.realShadow.assign(v.realShadow.begin(), v.realShadow.end());
    f.zeroShadow.resize(count);
    f.columns.resize(height);
    const Projector projector(camera);
    parallelFor(0, height, 16, [&](int64_t y) {
        glm::ivec2 span(width, -1);
        for (int x = 0; x < width; ++x) {
            const size_t i = static_cast<size_t>(y) * width + x;
            const bool real = s.realPoints[i].valid();
            f.realDepth[i] = real ? projector.depth(s.realPoints[i].position) : -1.0f;
            f.zeroShadow[i] = !real || f.realShadow[i] == glm::vec3(0.0f);
            if (!f.zeroShadow[i]) span = {std::min(span.x, x), x};
        }
        f.columns[y] = span;
    });
    const GBuffer& g = *s.gbuffer;
    f.rect = g.written;
    const size_t rectWidth = f.rect.empty() ? 0 : static_cast<size_t>(f.rect.x1 - f.rect.x0);
    const size_t rectCount = f.rect.empty() ? 0 : rectWidth * static_cast<size_t>(f.rect.y1 - f.rect.y0);
    f.objectDepth.resize(rectCount);
    f.objectIndex.resize(rectCount);
    f.objectRadiance.resize(rectCount);
    parallelFor(f.rect.y0, f.rect.y1, 8, [&](int64_t y) {
        size_t k = static_cast<size_t>(y - f.rect.y0) * rectWidth;
        for (int x = f.rect.x0; x < f.rect.x1; ++x, ++k) {
            const size_t i = static_cast<size_t>(y) * width + x;
            const SurfaceId& id = g.objectIds[i];
            const ptrdiff_t object = id.mesh ? id.mesh - s.objects.data() : -1;
            const bool known =
                object >= 0 && object < static_cast<ptrdiff_t>(s.objects.size()) && g.object[i].valid();
            f.objectIndex[k] = known ? static_cast<int32_t>(object) : -1;
            f.objectDepth[k] = known ? projector.depth(g.object[i].position) : -1.0f;
            f.objectRadiance[k] = known ? v.objectRadiance[i] : glm::vec3(0.0f);
        }
    });
    f.positions.resize(s.objects.size());
    for (size_t m = 0; m < s.objects.size(); ++m) f.positions[m] = s.objects[m].positions;
}

}  // namespace

TemporalStats TemporalReuse::apply(int frames, const TemporalSurfaces& s, TemporalValues v) {
    TemporalStats stats;
    if (frames <= 1) {
        history_.clear();
        return stats;
    }
    const Camera& camera = *s.camera;
    const int width = camera.width, height = camera.height;
    // Frames of another size are of no use (nor the ones before them); more than frames - 1 are not needed.
    const bool resized =
        !history_.empty() && (history_.front().width != width || history_.front().height != height);
    keepNewest(resized ? 0 : frames - 1);
    Frame current;
    if (!spare_.empty()) {
        current = std::move(spare_.back());
        spare_.pop_back();
    }
    record(s, v, current);

    if (!history_.empty()) {
        const GBuffer& g = *s.gbuffer;
        std::vector<Projector> there;
        std::vector<uint8_t> still;  // the kept frame's camera is this one: real points stay at their pixel
        // How each object moved since the kept frame: not at all (and the camera is the same: its points stay
        // at their pixel), by one shift of every vertex (a point was where it is now minus the shift), or
        // otherwise (a point was at its barycentric place between the kept vertices).
        std::vector<std::vector<ObjectMotion>> motion;
        for (const Frame& h : history_) {
            there.emplace_back(h.camera);
            still.push_back(h.camera == camera);
            std::vector<ObjectMotion>& moved = motion.emplace_back(s.objects.size());
            for (size_t m = 0; m < s.objects.size() && m < h.positions.size(); ++m)
                moved[m] = motionOf(h.positions[m], s.objects[m].positions, still.back());
        }
        // The real surfaces' change. Where it is 0 over the pixel's neighbourhood (most of the image: the
        // objects' shadows are small), the kept values clamp to 0 too: nothing to do.
        const std::vector<uint8_t>& zero = current.zeroShadow;
        const std::vector<glm::ivec2>& columns = current.columns;
        auto zeroAround = [&](int x, int y) {
            for (int yy = std::max(y - 1, 0); yy <= std::min(y + 1, height - 1); ++yy)
                for (int xx = std::max(x - 1, 0); xx <= std::min(x + 1, width - 1); ++xx)
                    if (!zero[static_cast<size_t>(yy) * width + xx]) return false;
            return true;
        };
        std::atomic<size_t> realSeen{0}, realAveraged{0}, objectSeen{0}, objectAveraged{0};
        parallelFor(0, height, 4, [&](int64_t y64) {
            const int y = static_cast<int>(y64);
            size_t seen = 0, averaged = 0;
            // Only the columns next to a non-zero value in this row or the ones above and below.
            glm::ivec2 span(width, -1);
            for (int yy = std::max(y - 1, 0); yy <= std::min(y + 1, height - 1); ++yy)
                span = {std::min(span.x, columns[yy].x), std::max(span.y, columns[yy].y)};
            for (int x = std::max(span.x - 1, 0); x <= std::min(span.y + 1, width - 1); ++x) {
                const size_t i = static_cast<size_t>(y) * width + x;
                if (current.realDepth[i] < 0.0f || zeroAround(x, y)) continue;
                const Range range = neighbourhood(current.realShadow, i, x, y, width, height,
                                                  [&](size_t j) { return current.realDepth[j] >= 0.0f; });
                if (range.flat()) continue;
                WindowMean window(current.realShadow[i], range);
                for (size_t k = 0; k < history_.size(); ++k) {
                    const Frame& h = history_[k];
                    Taps taps;
                    if (still[k]) {
                        if (h.realDepth[i] >= 0.0f) taps = samePixel(i);
                    } else {
                        glm::vec2 pixel;
                        float depth;
                        if (!there[k].project(s.realPoints[i].position, pixel, depth)) continue;
                        taps = bilinearTaps(pixel, h.width, h.height, [&](int tx, int ty) {
                            return closeDepth(h.realDepth[static_cast<size_t>(ty) * h.width + tx], depth);
                        });
                    }
                    if (taps.count > 0) window.add(fetch(taps, h.realShadow));
                }
                v.realShadow[i] = window.mean();
                ++seen;
                averaged += window.averaged();
            }
            realSeen += seen;
            realAveraged += averaged;
        });
        // The objects' radiance, following each point on its triangle.
        const PixelRect& r = current.rect;
        const int rectWidth = r.x1 - r.x0;
        parallelFor(r.y0, r.y1, 4, [&](int64_t y64) {
            const int y = static_cast<int>(y64);
            size_t seen = 0, averaged = 0;
            for (int x = r.x0; x < r.x1; ++x) {
                const size_t k = static_cast<size_t>(y - r.y0) * rectWidth + (x - r.x0);
                const int32_t object = current.objectIndex[k];
                if (object < 0) continue;
                const TriangleMesh& mesh = s.objects[object];
                const size_t i = static_cast<size_t>(y) * width + x;
                const SurfaceId& id = g.objectIds[i];
                if (id.triangle >= mesh.triangles.size()) continue;
                const Range range =
                    neighbourhood(current.objectRadiance, k, x - r.x0, y - r.y0, rectWidth, r.y1 - r.y0,
                                  [&](size_t j) { return current.objectIndex[j] == object; });
                if (range.flat()) continue;
                WindowMean window(current.objectRadiance[k], range);
                for (size_t f = 0; f < history_.size(); ++f) {
                    const Frame& h = history_[f];
                    if (static_cast<size_t>(object) >= h.positions.size() || h.rect.empty()) continue;
                    const ObjectMotion& moved = motion[f][object];
                    if (moved.kind == ObjectMotion::Kind::Changed) continue;
                    const int hw = h.rect.x1 - h.rect.x0;
                    auto accept = [&](int tx, int ty, float depth) {
                        const size_t j = static_cast<size_t>(ty) * hw + tx;
                        return h.objectIndex[j] == object && closeDepth(h.objectDepth[j], depth);
                    };
                    Taps taps;
                    if (moved.kind == ObjectMotion::Kind::Still) {
                        // Where it was: the same pixel, exactly.
                        const int tx = x - h.rect.x0, ty = y - h.rect.y0;
                        if (tx >= 0 && ty >= 0 && tx < hw && ty < h.rect.y1 - h.rect.y0 &&
                            accept(tx, ty, current.objectDepth[k]))
                            taps = samePixel(static_cast<size_t>(ty) * hw + tx);
                    } else {
                        glm::vec3 point = g.object[i].position - moved.shift;
                        if (moved.kind == ObjectMotion::Kind::Deformed) {
                            const std::vector<glm::vec3>& p = h.positions[object];
                            const glm::uvec3 tri = mesh.triangles[id.triangle];
                            const float u = id.barycentric.x, w = id.barycentric.y;
                            point = (1.0f - u - w) * p[tri.x] + u * p[tri.y] + w * p[tri.z];
                        }
                        glm::vec2 pixel;
                        float depth;
                        if (!there[f].project(point, pixel, depth)) continue;
                        taps =
                            bilinearTaps(pixel - glm::vec2(h.rect.x0, h.rect.y0), hw, h.rect.y1 - h.rect.y0,
                                         [&](int tx, int ty) { return accept(tx, ty, depth); });
                    }
                    if (taps.count > 0) window.add(fetch(taps, h.objectRadiance));
                }
                v.objectRadiance[i] = window.mean();
                ++seen;
                averaged += window.averaged();
            }
            objectSeen += seen;
            objectAveraged += averaged;
        });
        stats = {realSeen, realAveraged, objectSeen, objectAveraged};
    }
    history_.push_front(std::move(current));
    keepNewest(frames - 1);
    return stats;
}

void TemporalReuse::keepNewest(int count) {
    while (static_cast<int>(history_.size()) > count) {
        spare_.push_back(std::move(history_.back()));
        history_.pop_back();
    }
}

}  // namespace deltagi
