#include "live/marker_registration.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>
#include <glm/gtc/quaternion.hpp>

#include "core/environment.h"
#include "core/parallel.h"
#include "io/image_encode.h"

namespace deltagi {

std::array<glm::vec3, 4> markerCorners(const Marker& marker) {
    const float h = 0.5f * marker.size;
    return {glm::vec3(-h, -h, 0.0f), glm::vec3(h, -h, 0.0f), glm::vec3(h, h, 0.0f), glm::vec3(-h, h, 0.0f)};
}

std::vector<bool> markerCells(int id) {
    apriltag_family_t* family = tag36h11_create();
    std::vector<bool> cells;
    if (id >= 0 && static_cast<uint32_t>(id) < family->ncodes) {
        image_u8_t* image = apriltag_to_image(family, id);
        if (image && image->width == kMarkerCells && image->height == kMarkerCells)
            for (int y = 0; y < kMarkerCells; ++y)
                for (int x = 0; x < kMarkerCells; ++x)
                    cells.push_back(image->buf[static_cast<size_t>(y) * image->stride + x] < 128);
        image_u8_destroy(image);
    }
    tag36h11_destroy(family);
    return cells;
}

// ---- detection ------------------------------------------------------------------------------------------

// Frames at least this wide are searched for the markers' squares at half resolution
// (MarkerDetector::detect), except every kFullResolutionEvery-th frame.
constexpr int kHalfResolutionWidth = 640;
constexpr uint64_t kFullResolutionEvery = 8;

struct MarkerDetector::Impl {
    apriltag_family_t* family = nullptr;
    apriltag_detector_t* detector = nullptr;
    std::vector<int> markerOfId;  // tag id -> index into the markers, -1 where none
    int lastKnown = 0;            // how many of the scene's markers the last frame showed (detect())
    uint64_t frames = 0;          // the frames searched
};

MarkerDetector::MarkerDetector(std::span<const Marker> markers) : impl_(std::make_unique<Impl>()) {
    impl_->family = tag36h11_create();
    impl_->detector = apriltag_detector_create();
    apriltag_detector_add_family(impl_->detector, impl_->family);
    // The squares found in a slightly blurred copy (a noisy frame's segments hold together), their edges
    // refined on the frame itself. One thread: the same corners on any machine. (The resolution the squares
    // are found at is detect()'s.)
    impl_->detector->quad_sigma = 0.8f;
    impl_->detector->refine_edges = true;
    impl_->detector->nthreads = 1;
    impl_->markerOfId.assign(impl_->family->ncodes, -1);
    for (size_t i = 0; i < markers.size(); ++i)
        if (markers[i].id >= 0 && static_cast<uint32_t>(markers[i].id) < impl_->family->ncodes)
            impl_->markerOfId[markers[i].id] = static_cast<int>(i);
}

MarkerDetector::~MarkerDetector() {
    apriltag_detector_destroy(impl_->detector);
    tag36h11_destroy(impl_->family);
}

namespace {

// A frame's grey levels in linear light, for the corners' refinement.
struct GreyImage {
    int width = 0, height = 0;
    std::vector<float> values;
    float at(int x, int y) const {
        x = std::clamp(x, 0, width - 1), y = std::clamp(y, 0, height - 1);
        return values[static_cast<size_t>(y) * width + x];
    }
    // Bilinear, at a point in our pixel coordinates (pixel centres at + 0.5).
    float sample(glm::dvec2 p) const {
        const double x = p.x - 0.5, y = p.y - 0.5;
        const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
        const float fx = static_cast<float>(x - x0), fy = static_cast<float>(y - y0);
        return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
               fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
    }
};

// Where the black square's edge from corner a to corner b lies: at points along it, the place across it where
// the grey level is half-way between the black inside and the white outside (in linear light, where an edge
// blurred by the lens and the pixels' area is crossed half-way at the edge itself), and the line through
// them. Nothing when too few points are found. `outward`: the normal pointing out of the square.
struct EdgeLine {
    glm::dvec2 point, direction;
};
std::optional<EdgeLine> fitEdge(const GreyImage& grey, glm::dvec2 a, glm::dvec2 b, glm::dvec2 outward,
                                double cellPx) {
    const double length = glm::length(b - a);
    const glm::dvec2 along = (b - a) / length;
    // Across the edge: within the black border inside and the white ring outside (each a cell wide).
    const double reach = std::clamp(0.7 * cellPx, 1.0, 3.0);
    const int samples = std::max(6, static_cast<int>(length / 1.5));
    std::vector<glm::dvec2> points;
    for (int i = 0; i < samples; ++i) {
        // Away from the corners, where the neighbouring edges blur in.
        const double t = 0.15 + 0.7 * (i + 0.5) / samples;
        const glm::dvec2 p = a + t * length * along;
        constexpr int kSteps = 24;
        float profile[kSteps + 1];
        for (int k = 0; k <= kSteps; ++k)
            profile[k] = grey.sample(p + outward * (-reach + 2.0 * reach * k / kSteps));
        const float black = std::min({profile[0], profile[1], profile[2]});
        const float white = std::max({profile[kSteps], profile[kSteps - 1], profile[kSteps - 2]});
        if (!(white - black > 0.02f)) continue;
        const float half = 0.5f * (black + white);
        for (int k = 0; k < kSteps; ++k)
            if (profile[k] < half && profile[k + 1] >= half) {
                const double f = (half - profile[k]) / (profile[k + 1] - profile[k]);
                const double across = -reach + 2.0 * reach * (k + f) / kSteps;
                points.push_back(p + outward * across);
                break;
            }
    }
    if (points.size() < 4) return std::nullopt;
    // The line through them (their mean and principal direction).
    glm::dvec2 mean(0.0);
    for (glm::dvec2 q : points) mean += q / static_cast<double>(points.size());
    double sxx = 0, sxy = 0, syy = 0;
    for (glm::dvec2 q : points) {
        const glm::dvec2 d = q - mean;
        sxx += d.x * d.x, sxy += d.x * d.y, syy += d.y * d.y;
    }
    const double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
    return EdgeLine{mean, glm::dvec2(std::cos(angle), std::sin(angle))};
}

// The corners where the fitted edges meet; the detector's where an edge cannot be fitted or the lines meet
// far from them.
void refineCorners(const GreyImage& grey, std::array<glm::dvec2, 4>& corners) {
    glm::dvec2 centre(0.0);
    for (glm::dvec2 c : corners) centre += 0.25 * c;
    double side = 0.0;
    for (int k = 0; k < 4; ++k) side += 0.25 * glm::length(corners[(k + 1) % 4] - corners[k]);
    const double cellPx = side / 8.0;
    std::array<std::optional<EdgeLine>, 4> edges;
    for (int k = 0; k < 4; ++k) {
        const glm::dvec2 a = corners[k], b = corners[(k + 1) % 4];
        glm::dvec2 normal = glm::normalize(glm::dvec2(b.y - a.y, a.x - b.x));
        if (glm::dot(normal, 0.5 * (a + b) - centre) < 0.0) normal = -normal;
        edges[k] = fitEdge(grey, a, b, normal, cellPx);
    }
    const std::array<glm::dvec2, 4> detected = corners;
    for (int k = 0; k < 4; ++k) {
        // Corner k is where edge k - 1 (from corner k - 1) meets edge k.
        const auto& e0 = edges[(k + 3) % 4];
        const auto& e1 = edges[k];
        if (!e0 || !e1) continue;
        const double cross = e0->direction.x * e1->direction.y - e0->direction.y * e1->direction.x;
        if (std::abs(cross) < 0.1) continue;
        const glm::dvec2 d = e1->point - e0->point;
        const double t = (d.x * e1->direction.y - d.y * e1->direction.x) / cross;
        const glm::dvec2 corner = e0->point + t * e0->direction;
        if (glm::length(corner - detected[k]) < 0.5 * cellPx) corners[k] = corner;
    }
}

}  // namespace

MarkerDetector::Result MarkerDetector::detect(const Image& frame) {
    Result result;
    if (frame.empty()) return result;
    // The detector finds and decodes the squares in sRGB-encoded grey levels (what cameras give and it is
    // tuned for); their corners are then refined in linear light (refineCorners).
    GreyImage linear{frame.width(), frame.height(), std::vector<float>(frame.pixelCount())};
    image_u8_t* grey =
        image_u8_create(static_cast<unsigned>(frame.width()), static_cast<unsigned>(frame.height()));
    parallelFor(0, frame.height(), 16, [&](int64_t y) {
        for (int x = 0; x < frame.width(); ++x) {
            const float l = luminance(frame.rgb(x, static_cast<int>(y)));
            const float v = std::clamp(std::isfinite(l) ? l : 0.0f, 0.0f, 1.0f);
            linear.values[static_cast<size_t>(y) * frame.width() + x] = v;
            grey->buf[static_cast<size_t>(y) * grey->stride + x] = linearToSrgb8(v);
        }
    });
    // Squares are searched for at half resolution in frames kHalfResolutionWidth wide or more (a third of the
    // time; the decoding and the corners' refinement use the full frame; a 12 cm marker 1 m away is still 40
    // pixels wide there, as in a 320x240 frame at full resolution). When that finds fewer of the scene's
    // markers than the last frame showed, or none, the full resolution is searched too; and every
    // kFullResolutionEvery-th frame, so that a small marker that comes into view beside a larger one is
    // found.
    auto knownMarkers = [&](const zarray_t* found) {
        int known = 0;
        for (int i = 0; i < zarray_size(found); ++i) {
            apriltag_detection_t* d = nullptr;
            zarray_get(found, i, &d);
            known += d->id >= 0 && static_cast<size_t>(d->id) < impl_->markerOfId.size() &&
                     impl_->markerOfId[d->id] >= 0;
        }
        return known;
    };
    const bool halfResolution =
        frame.width() >= kHalfResolutionWidth && impl_->frames++ % kFullResolutionEvery != 0;
    impl_->detector->quad_decimate = halfResolution ? 2.0f : 1.0f;
    zarray_t* detections = apriltag_detector_detect(impl_->detector, grey);
    if (halfResolution) {
        const int known = knownMarkers(detections);
        if (known == 0 || known < impl_->lastKnown) {
            apriltag_detections_destroy(detections);
            impl_->detector->quad_decimate = 1.0f;
            detections = apriltag_detector_detect(impl_->detector, grey);
        }
    }
    for (int i = 0; i < zarray_size(detections); ++i) {
        apriltag_detection_t* d = nullptr;
        zarray_get(detections, i, &d);
        const int marker = d->id >= 0 && static_cast<size_t>(d->id) < impl_->markerOfId.size()
                               ? impl_->markerOfId[d->id]
                               : -1;
        if (marker < 0) {
            ++result.unknown;
            continue;
        }
        MarkerSighting s;
        s.marker = marker;
        s.decisionMargin = d->decision_margin;
        double shortest = INFINITY;
        for (int k = 0; k < 4; ++k) {
            // libapriltag's pixel centres are at + 0.5, as ours (its decimation's corner mapping says so).
            s.corners[k] = glm::dvec2(d->p[k][0], d->p[k][1]);
        }
        for (int k = 0; k < 4; ++k)
            shortest = std::min(shortest, glm::length(s.corners[k] - s.corners[(k + 1) % 4]));
        if (!(shortest >= kMinMarkerSidePx)) {
            ++result.tooSmall;
            continue;
        }
        refineCorners(linear, s.corners);
        result.sightings.push_back(s);
    }
    impl_->lastKnown = static_cast<int>(result.sightings.size()) + result.tooSmall;
    apriltag_detections_destroy(detections);
    image_u8_destroy(grey);
    // In the scene's order, so that the pose does not depend on the detector's.
    std::sort(result.sightings.begin(), result.sightings.end(),
              [](const MarkerSighting& a, const MarkerSighting& b) { return a.marker < b.marker; });
    return result;
}

// ---- pose -----------------------------------------------------------------------------------------------

namespace {

// Solves A x = b (n x n, row-major) by Gaussian elimination with partial pivoting; false when singular.
template <int N>
bool solveLinear(std::array<double, N * N> a, std::array<double, N> b, std::array<double, N>& x) {
    for (int c = 0; c < N; ++c) {
        int pivot = c;
        for (int r = c + 1; r < N; ++r)
            if (std::abs(a[r * N + c]) > std::abs(a[pivot * N + c])) pivot = r;
        if (!(std::abs(a[pivot * N + c]) > 1e-300)) return false;
        if (pivot != c) {
            for (int k = 0; k < N; ++k) std::swap(a[c * N + k], a[pivot * N + k]);
            std::swap(b[c], b[pivot]);
        }
        for (int r = c + 1; r < N; ++r) {
            const double f = a[r * N + c] / a[c * N + c];
            for (int k = c; k < N; ++k) a[r * N + k] -= f * a[c * N + k];
            b[r] -= f * b[c];
        }
    }
    for (int r = N - 1; r >= 0; --r) {
        double s = b[r];
        for (int k = r + 1; k < N; ++k) s -= a[r * N + k] * x[k];
        x[r] = s / a[r * N + r];
    }
    return true;
}

// A rigid transform in the computer-vision camera frame (x right, y down, z forward): q = R p + t.
struct RigidPose {
    glm::dmat3 r{1.0};
    glm::dvec3 t{0.0};
};

// The OpenGL camera frame (x right, y up, z backwards) from the computer-vision one, and back.
const glm::dmat3 kFlipYZ(1, 0, 0, 0, -1, 0, 0, 0, -1);

RigidPose poseOf(const glm::mat4& worldFromCamera) {
    const glm::dmat4 cameraFromWorld = glm::inverse(glm::dmat4(worldFromCamera));
    return {kFlipYZ * glm::dmat3(cameraFromWorld), kFlipYZ * glm::dvec3(cameraFromWorld[3])};
}

glm::mat4 worldFromCameraOf(const RigidPose& pose) {
    glm::dmat4 cameraFromWorld(kFlipYZ * pose.r);
    cameraFromWorld[3] = glm::dvec4(kFlipYZ * pose.t, 1.0);
    return glm::mat4(glm::inverse(cameraFromWorld));
}

// The rotation nearest to m (polar decomposition by Newton's iteration).
glm::dmat3 nearestRotation(glm::dmat3 m) {
    for (int i = 0; i < 20; ++i) m = 0.5 * (m + glm::transpose(glm::inverse(m)));
    return m;
}

glm::dmat3 rotationFromVector(glm::dvec3 w) {
    const double angle = glm::length(w);
    if (angle < 1e-12) return glm::dmat3(1.0) + glm::dmat3(0, w.z, -w.y, -w.z, 0, w.x, w.y, -w.x, 0);
    const glm::dvec3 k = w / angle;
    const glm::dmat3 kx(0, k.z, -k.y, -k.z, 0, k.x, k.y, -k.x, 0);  // columns: cross(k, .)
    return glm::dmat3(1.0) + std::sin(angle) * kx + (1.0 - std::cos(angle)) * kx * kx;
}

// The pose of a plane (its points (x, y, 0)) from four or more points and their undistorted normalized image
// coordinates: a homography, split into rotation and translation (Zhang 2000).
std::optional<RigidPose> planePose(std::span<const glm::dvec2> plane, std::span<const glm::dvec2> image) {
    // h33 = 1: 8 unknowns, least squares over the points.
    std::array<double, 64> ata{};
    std::array<double, 8> atb{};
    for (size_t i = 0; i < plane.size(); ++i) {
        const double x = plane[i].x, y = plane[i].y, u = image[i].x, v = image[i].y;
        const double rows[2][9] = {{x, y, 1, 0, 0, 0, -u * x, -u * y, u},
                                   {0, 0, 0, x, y, 1, -v * x, -v * y, v}};
        for (const auto& row : rows)
            for (int a = 0; a < 8; ++a) {
                for (int b = 0; b < 8; ++b) ata[a * 8 + b] += row[a] * row[b];
                atb[a] += row[a] * row[8];
            }
    }
    std::array<double, 8> h{};
    if (!solveLinear<8>(ata, atb, h)) return std::nullopt;
    const glm::dvec3 h1(h[0], h[3], h[6]), h2(h[1], h[4], h[7]), h3(h[2], h[5], 1.0);
    double scale = 2.0 / (glm::length(h1) + glm::length(h2));
    if (h3.z * scale < 0.0) scale = -scale;  // in front of the camera
    const glm::dvec3 r1 = h1 * scale, r2 = h2 * scale;
    RigidPose pose;
    pose.r = nearestRotation(glm::dmat3(r1, r2, glm::cross(r1, r2)));
    pose.t = h3 * scale;
    if (!std::isfinite(pose.t.x + pose.t.y + pose.t.z)) return std::nullopt;
    return pose;
}

// The Gauss-Newton normal equations of the normalized reprojection error of points (world) seen at
// `observed`, at `pose`: J^T J and J^T e over the parameters (rotation w, translation),
// q' = exp(w) R p + t + dt.
void normalEquations(const RigidPose& pose, std::span<const glm::dvec3> points,
                     std::span<const glm::dvec2> observed, std::array<double, 36>& jtj,
                     std::array<double, 6>& jte) {
    jtj.fill(0.0);
    jte.fill(0.0);
    for (size_t i = 0; i < points.size(); ++i) {
        const glm::dvec3 rp = pose.r * points[i];
        const glm::dvec3 q = rp + pose.t;
        const double iz = 1.0 / q.z;
        const glm::dvec2 e = glm::dvec2(q.x, q.y) * iz - observed[i];
        // d(projection)/dq, and dq/d(rotation w, translation).
        const glm::dvec3 du(iz, 0.0, -q.x * iz * iz), dv(0.0, iz, -q.y * iz * iz);
        auto rowFor = [&](glm::dvec3 d) {
            // d/dw of exp(w) rp = w x rp: -rp x, i.e. column k is e_k x rp.
            const glm::dvec3 dw = glm::cross(rp, d);  // d . (e_k x rp) = e_k . (rp x d)
            return std::array<double, 6>{dw.x, dw.y, dw.z, d.x, d.y, d.z};
        };
        const std::array<double, 6> ju = rowFor(du), jv = rowFor(dv);
        for (int a = 0; a < 6; ++a) {
            for (int b = 0; b < 6; ++b) jtj[a * 6 + b] += ju[a] * ju[b] + jv[a] * jv[b];
            jte[a] += ju[a] * e.x + jv[a] * e.y;
        }
    }
}

// How far a refined corner may be from the true one in x and in y (pixels): the noise poses are judged by.
constexpr double kCornerNoisePx = 0.3;

// The camera's position c = -R^T t of a pose, and its change with the parameters (rotation w, translation;
// exp(w) R, t + dt): -R^T ([t]x w + dt), rows of G = -R^T [[t]x | I].
glm::dvec3 cameraPositionOf(const RigidPose& pose) {
    return -glm::transpose(pose.r) * pose.t;
}
std::array<std::array<double, 6>, 3> cameraPositionJacobian(const RigidPose& pose) {
    const glm::dmat3 rt = glm::transpose(pose.r);
    const glm::dvec3 t = pose.t;
    const glm::dmat3 tx(0, t.z, -t.y, -t.z, 0, t.x, t.y, -t.x, 0);  // columns: cross(t, .)
    const glm::dmat3 left = rt * tx;
    std::array<std::array<double, 6>, 3> g{};
    for (int row = 0; row < 3; ++row)
        for (int c = 0; c < 3; ++c) {
            g[row][c] = -left[c][row];
            g[row][3 + c] = -rt[c][row];
        }
    return g;
}

// Where the camera was (`position`) and how far it may have gone since (`sigma`, world units): a term of
// the refinement, |c - position|^2 / sigma^2, against the corners' |e|^2 / noise^2. It holds the poses
// that the corners alone barely tell apart (one small marker) near the last one, and moves a pose the
// corners fix by a small part of the way.
struct PositionPrior {
    glm::dvec3 position{0.0};
    double weight = 0.0;  // (noise / sigma)^2, noise in normalized units: 0 is no prior
};

// Gauss-Newton (with a little damping) on the normalized reprojection error of points p (world) seen at n,
// plus the prior's term; returns the sum of squared errors it ends with (the prior's term included).
double refinePose(RigidPose& pose, std::span<const glm::dvec3> points, std::span<const glm::dvec2> observed,
                  const PositionPrior& prior = {}) {
    double lambda = 1e-6;
    auto cost = [&](const RigidPose& p) {
        const glm::dvec3 away = cameraPositionOf(p) - prior.position;
        double c = prior.weight * glm::dot(away, away);
        for (size_t i = 0; i < points.size(); ++i) {
            const glm::dvec3 q = p.r * points[i] + p.t;
            if (!(q.z > 0.0)) return static_cast<double>(INFINITY);
            const glm::dvec2 e = glm::dvec2(q.x, q.y) / q.z - observed[i];
            c += glm::dot(e, e);
        }
        return c;
    };
    double current = cost(pose);
    for (int iteration = 0; iteration < 30 && std::isfinite(current); ++iteration) {
        std::array<double, 36> jtj{};
        std::array<double, 6> jte{};
        normalEquations(pose, points, observed, jtj, jte);
        if (prior.weight > 0.0) {
            const glm::dvec3 away = cameraPositionOf(pose) - prior.position;
            const std::array<std::array<double, 6>, 3> g = cameraPositionJacobian(pose);
            for (int row = 0; row < 3; ++row)
                for (int a = 0; a < 6; ++a) {
                    for (int b = 0; b < 6; ++b) jtj[a * 6 + b] += prior.weight * g[row][a] * g[row][b];
                    jte[a] += prior.weight * g[row][a] * away[row];
                }
        }
        bool improved = false;
        for (int attempt = 0; attempt < 10 && !improved; ++attempt) {
            std::array<double, 36> damped = jtj;
            for (int a = 0; a < 6; ++a) damped[a * 7] *= 1.0 + lambda;
            std::array<double, 6> neg{}, step{};
            for (int a = 0; a < 6; ++a) neg[a] = -jte[a];
            if (!solveLinear<6>(damped, neg, step)) return current;
            RigidPose next;
            next.r = rotationFromVector({step[0], step[1], step[2]}) * pose.r;
            next.t = pose.t + glm::dvec3(step[3], step[4], step[5]);
            const double c = cost(next);
            if (c < current) {
                pose = next;
                const bool converged = current - c < 1e-14 * (1.0 + current);
                current = c;
                lambda = std::max(lambda * 0.1, 1e-9);
                improved = true;
                if (converged) return current;
            } else {
                lambda *= 10.0;
            }
        }
        if (!improved) return current;
    }
    return current;
}

// The standard deviation of the camera's position (world units; the root of its covariance's trace) at
// `pose`, were each corner's x and y off by `noise` (normalized units) at random: the pose's covariance
// noise^2 (J^T J)^-1, taken through the camera position (cameraPositionJacobian).
// Infinite where the corners do not fix the pose.
double cameraPositionSigma(const RigidPose& pose, std::span<const glm::dvec3> points, double noise) {
    std::array<double, 36> jtj;
    std::array<double, 6> unused;
    std::vector<glm::dvec2> exact(points.size());  // the residuals play no part
    normalEquations(pose, points, exact, jtj, unused);
    std::array<double, 36> covariance{};  // column k: (J^T J)^-1 e_k
    for (int k = 0; k < 6; ++k) {
        std::array<double, 6> unit{}, column{};
        unit[k] = 1.0;
        if (!solveLinear<6>(jtj, unit, column)) return INFINITY;
        for (int a = 0; a < 6; ++a) covariance[a * 6 + k] = column[a];
    }
    // The position's variance: trace(G C G^T) noise^2.
    double variance = 0.0;
    for (const std::array<double, 6>& g : cameraPositionJacobian(pose))
        for (int a = 0; a < 6; ++a)
            for (int b = 0; b < 6; ++b) variance += g[a] * covariance[a * 6 + b] * g[b];
    return variance >= 0.0 ? noise * std::sqrt(variance) : INFINITY;
}

}  // namespace

std::optional<MarkerPose> solveCameraPose(std::span<const MarkerSighting> sightings,
                                          std::span<const Marker> markers, const Camera& camera,
                                          const std::optional<glm::mat4>& previous, double previousSigma) {
    if (sightings.empty() || !(camera.fx > 0.0f) || !(camera.fy > 0.0f)) return std::nullopt;
    // Every corner: its world point and its undistorted normalized image point.
    std::vector<glm::dvec3> world;
    std::vector<glm::dvec2> normalized;
    auto normalize = [&](glm::dvec2 pixel) {
        glm::vec2 n(static_cast<float>((pixel.x - camera.cx) / camera.fx),
                    static_cast<float>((pixel.y - camera.cy) / camera.fy));
        if (!camera.distortion.none()) n = camera.distortion.undistort(n);
        return glm::dvec2(n);
    };
    size_t largest = 0;
    double largestArea = -1.0;
    for (size_t s = 0; s < sightings.size(); ++s) {
        const Marker& marker = markers[sightings[s].marker];
        const std::array<glm::vec3, 4> corners = markerCorners(marker);
        for (int k = 0; k < 4; ++k) {
            world.emplace_back(glm::dvec3(marker.worldFromMarker * glm::vec4(corners[k], 1.0f)));
            normalized.push_back(normalize(sightings[s].corners[k]));
        }
        const auto& c = sightings[s].corners;
        const glm::dvec2 d1 = c[2] - c[0], d2 = c[3] - c[1];
        const double area = 0.5 * std::abs(d1.x * d2.y - d1.y * d2.x);
        if (area > largestArea) largestArea = area, largest = s;
    }
    // A first pose from the largest marker's homography, in its own frame, then taken to the world's.
    const Marker& first = markers[sightings[largest].marker];
    const std::array<glm::vec3, 4> corners = markerCorners(first);
    std::array<glm::dvec2, 4> plane, image;
    for (int k = 0; k < 4; ++k) {
        plane[k] = glm::dvec2(corners[k]);
        image[k] = normalized[largest * 4 + k];
    }
    std::optional<RigidPose> fromMarker = planePose(plane, image);
    if (!fromMarker) return std::nullopt;
    // A small square seen nearly head-on looks almost the same tilted either way about the line of sight (the
    // planar pose ambiguity: two minima of the reprojection error, the camera some 2 x tilt x distance
    // apart). The pose is refined from the homography's, from it with the marker's normal reflected about the
    // line of sight, and from `previous`; the lowest error wins, or among those close to it, the one nearest
    // `previous`.
    std::vector<RigidPose> starts = {*fromMarker};
    const glm::dvec3 n = fromMarker->r[2], v = glm::normalize(fromMarker->t);
    const glm::dvec3 reflected = 2.0 * glm::dot(v, n) * v - n;
    const glm::dvec3 axis = glm::cross(n, reflected);
    if (glm::length(axis) > 1e-9) {
        const double angle = std::atan2(glm::length(axis), glm::dot(n, reflected));
        RigidPose other = *fromMarker;
        other.r = rotationFromVector(glm::normalize(axis) * angle) * fromMarker->r;
        starts.push_back(other);
    }
    const glm::dmat4 markerFromWorld = glm::inverse(glm::dmat4(first.worldFromMarker));
    std::vector<std::pair<RigidPose, double>> solutions;
    for (const RigidPose& start : starts) {
        RigidPose p;
        p.r = start.r * glm::dmat3(markerFromWorld);
        p.t = start.r * glm::dvec3(markerFromWorld[3]) + start.t;
        const double cost = refinePose(p, world, normalized);
        if (std::isfinite(cost)) solutions.emplace_back(p, cost);
    }
    // And from the last frame's pose, which finds the minimum near it when the other starts do not.
    if (previous) {
        RigidPose p = poseOf(*previous);
        const double cost = refinePose(p, world, normalized);
        if (std::isfinite(cost)) solutions.emplace_back(p, cost);
    }
    if (solutions.empty()) return std::nullopt;
    std::sort(solutions.begin(), solutions.end(),
              [](const auto& a, const auto& b) { return a.second < b.second; });
    RigidPose pose = solutions.front().first;
    // The solutions that explain the corners about as well as the best: within 4 times its squared error plus
    // what corners 0.3 pixels off in x and y add (one marker's 4 corners fit a wrong tilt better than the
    // true one by that much).
    const double pixel = 1.0 / std::max<double>(camera.fy, 1.0);  // a pixel in normalized units
    const double noise =
        2.0 * static_cast<double>(world.size()) * (kCornerNoisePx * pixel) * (kCornerNoisePx * pixel);
    auto plausible = [&](double cost) { return cost <= 4.0 * solutions.front().second + noise; };
    // Two of them are distinct minima when their cameras lie further apart than kDistinctMinima of the
    // camera's distance from the marker (the same minimum reached from two starts differs by rounding).
    constexpr double kDistinctMinima = 0.01;
    const double reach =
        kDistinctMinima * glm::length(cameraPositionOf(pose) - glm::dvec3(first.worldFromMarker[3]));
    double spread = 0.0;  // between the plausible solutions' cameras
    for (const auto& [candidate, cost] : solutions)
        if (plausible(cost))
            spread = std::max(spread, glm::length(cameraPositionOf(candidate) - cameraPositionOf(pose)));
    const bool ambiguous = spread > reach;
    if (previous) {
        // Of the plausible solutions, the one nearest the last frame's camera.
        const glm::dvec3 last = glm::dvec3((*previous)[3]);
        double nearest = glm::length(cameraPositionOf(pose) - last);
        for (const auto& [candidate, cost] : solutions)
            if (plausible(cost) && glm::length(cameraPositionOf(candidate) - last) < nearest) {
                pose = candidate;
                nearest = glm::length(cameraPositionOf(candidate) - last);
            }
    }
    if (previous && previousSigma > 0.0) {
        const double noiseNormalized = kCornerNoisePx * pixel;
        const PositionPrior prior{glm::dvec3((*previous)[3]),
                                  (noiseNormalized / previousSigma) * (noiseNormalized / previousSigma)};
        RigidPose held = pose;
        if (std::isfinite(refinePose(held, world, normalized, prior))) pose = held;
    }
    MarkerPose result;
    result.ambiguous = ambiguous;
    // Distinct minima: the camera is as uncertain as they are apart.
    result.positionSigma =
        std::max(cameraPositionSigma(pose, world, kCornerNoisePx * pixel), ambiguous ? spread : 0.0);
    result.markerDistance = glm::length(cameraPositionOf(pose) - glm::dvec3(first.worldFromMarker[3]));
    result.worldFromCamera = worldFromCameraOf(pose);
    result.markersSeen = static_cast<int>(sightings.size());
    // The RMS pixel error through the lens model.
    double squared = 0.0;
    for (size_t i = 0; i < world.size(); ++i) {
        const glm::dvec3 q = pose.r * world[i] + pose.t;
        if (!(q.z > 0.0)) return std::nullopt;
        const glm::vec3 qGl(static_cast<float>(q.x), static_cast<float>(-q.y), static_cast<float>(-q.z));
        const glm::dvec2 projected(camera.imagePoint(qGl));
        const size_t s = i / 4, k = i % 4;
        const glm::dvec2 e = projected - sightings[s].corners[k];
        squared += glm::dot(e, e);
    }
    result.reprojectionErrorPx = std::sqrt(squared / static_cast<double>(world.size()));
    const glm::mat4& m = result.worldFromCamera;
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            if (!std::isfinite(m[c][r])) return std::nullopt;
    if (!std::isfinite(result.reprojectionErrorPx)) return std::nullopt;
    return result;
}

// ---- smoothing ------------------------------------------------------------------------------------------

namespace {

// The exponential smoothing factor of a low-pass filter with cut-off `hz` over a step of `dt` seconds.
double smoothingFactor(double dt, double hz) {
    const double tau = 1.0 / (2.0 * std::numbers::pi * hz);
    return 1.0 / (1.0 + tau / dt);
}

// One One-Euro step of a vector value: the speed low-passed at the derivative cut-off, the value at a cut-off
// that rises with the speed's magnitude.
template <typename V>
void oneEuroStep(V& value, V& speed, const V& sample, double dt, double minCutoff, double beta,
                 double derivativeCutoff) {
    const V rawSpeed = (sample - value) / dt;
    speed += (rawSpeed - speed) * smoothingFactor(dt, derivativeCutoff);
    const double cutoff = minCutoff + beta * glm::length(speed);
    value += (sample - value) * smoothingFactor(dt, cutoff);
}

}  // namespace

glm::mat4 PoseFilter::filter(const glm::mat4& worldFromCamera, double timeSeconds) {
    const glm::dvec3 position(worldFromCamera[3]);
    glm::dquat q = glm::quat_cast(glm::dmat3(glm::mat3(worldFromCamera)));
    glm::dvec4 rotation(q.x, q.y, q.z, q.w);
    const double dt = timeSeconds - lastTime_;
    if (!smoothing_.enabled || !started_ || !(dt > 0.0)) {
        started_ = true;
        lastTime_ = timeSeconds;
        position_ = position;
        rotation_ = rotation;
        positionSpeed_ = glm::dvec3(0.0);
        rotationSpeed_ = glm::dvec4(0.0);
        return worldFromCamera;
    }
    lastTime_ = timeSeconds;
    if (glm::dot(rotation, rotation_) < 0.0) rotation = -rotation;  // the same rotation, nearer
    oneEuroStep(position_, positionSpeed_, position, dt, smoothing_.minCutoffHz, smoothing_.positionBeta,
                smoothing_.derivativeCutoffHz);
    // A quaternion's components change at half the angular speed (radians per second).
    oneEuroStep(rotation_, rotationSpeed_, rotation, dt, smoothing_.minCutoffHz,
                2.0 * smoothing_.rotationBeta, smoothing_.derivativeCutoffHz);
    rotation_ = glm::normalize(rotation_);
    const glm::dquat smoothed(rotation_.w, rotation_.x, rotation_.y, rotation_.z);
    glm::dmat4 out(glm::mat3_cast(smoothed));
    out[3] = glm::dvec4(position_, 1.0);
    return glm::mat4(out);
}

// ---- tracking -------------------------------------------------------------------------------------------

MarkerTracker::MarkerTracker(std::span<const Marker> markers, const Camera& camera, TrackingOptions options)
    : markers_(markers.begin(), markers.end()),
      camera_(camera),
      options_(options),
      detector_(markers),
      filter_(options.smoothing) {}

TrackedFrame MarkerTracker::track(const Image& frame, double timeSeconds) {
    TrackedFrame out;
    const MarkerDetector::Result found = detector_.detect(frame);
    out.unknownTags = found.unknown;
    out.tooSmall = found.tooSmall;
    const std::optional<glm::mat4> previous = lastSeen_ ? std::optional<glm::mat4>(lastRaw_) : std::nullopt;
    // How far the camera may have gone since the last registered frame (plus 1 cm): the prior's width.
    constexpr double kSlack = 0.01;
    const double reach =
        lastSeen_ ? options_.maxSpeed * std::max(timeSeconds - *lastSeen_, 0.0) + kSlack : 0.0;
    std::optional<MarkerPose> pose =
        solveCameraPose(found.sightings, markers_, camera_, previous, options_.maxSpeed > 0.0 ? reach : 0.0);
    const bool recent = lastSeen_ && timeSeconds - *lastSeen_ <= options_.holdSeconds;
    // More markers than the last registered frame saw fix the camera better than it was: always taken.
    if (pose && recent && options_.maxSpeed > 0.0 && pose->markersSeen <= lastMarkersSeen_) {
        const double moved = glm::distance(glm::dvec3(pose->worldFromCamera[3]), glm::dvec3(lastRaw_[3]));
        if (moved > reach) {
            out.jumped = true;
            out.markersSeen = pose->markersSeen;
            pose.reset();
        }
    }
    // An uncertain pose (one small marker alone: its corners fit cameras tens of centimetres apart about as
    // well) is a guess without an earlier pose to choose by, and the refinement's prior holds it near the
    // last one only while the camera cannot have gone further than the corners are uncertain: taken then,
    // otherwise treated as no marker. So a stream starts from a certain pose.
    if (pose && !(pose->positionSigma <= options_.certainSigma * pose->markerDistance)) {
        const bool priorHolds = previous && options_.maxSpeed > 0.0 && reach <= pose->positionSigma;
        const bool open = previous && options_.maxSpeed == 0.0;  // every pose taken
        if (!priorHolds && !open) {
            out.uncertain = true;
            out.markersSeen = pose->markersSeen;
            pose.reset();
        }
    }
    if (pose) {
        lastRaw_ = pose->worldFromCamera;
        lastMarkersSeen_ = pose->markersSeen;
        out.state = TrackedFrame::State::Registered;
        out.worldFromCamera = filter_.filter(pose->worldFromCamera, timeSeconds);
        out.reprojectionErrorPx = pose->reprojectionErrorPx;
        out.markersSeen = pose->markersSeen;
        lastSeen_ = timeSeconds;
        lastPose_ = out.worldFromCamera;
        return out;
    }
    if (recent) {
        out.state = TrackedFrame::State::Held;
        out.worldFromCamera = lastPose_;
        return out;
    }
    // Lost: the next sighting starts the filter afresh rather than gliding from an old pose.
    filter_.reset();
    return out;
}

}  // namespace deltagi
