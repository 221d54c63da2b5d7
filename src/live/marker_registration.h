// Registration by marker (the paper's §4: a scene camera registered to the pre-reconstructed scene by marker
// tracking): AprilTag tag36h11 markers that the scene file places on the reconstruction ("markers") are
// found in each camera frame, the camera's pose is solved from the corners of all the markers it sees with
// its intrinsics and lens distortion, and smoothed over time with a One-Euro filter (Casiez et al. 2012), so
// that a still camera gives a still object and a moving one follows without visible lag.
//
// Corners: libapriltag finds and decodes the squares in the sRGB-encoded grey image; each edge of a black
// square is then fitted with a line through the points where the grey level, in linear light, is half-way
// between the black border and the white ring across it, and the corners are where those lines meet (a
// tenth of a pixel; the detector's own corners, refined in sRGB values, put a 320x240 camera 5 times further
// off, tests/live/marker_registration_test.cpp). The pose minimises the reprojection error of every corner
// (Gauss-Newton from a homography of the largest marker, and from its mirror tilt: see solveCameraPose).
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "deltagi/image.h"
#include "deltagi/scene.h"

namespace deltagi {

// A marker's four corners in its own frame: bottom-left, bottom-right, top-right, top-left as printed (the
// order of MarkerSighting::corners).
std::array<glm::vec3, 4> markerCorners(const Marker& marker);

// A tag36h11 marker as printed: kMarkerCells x kMarkerCells cells, row by row from the top, true for black.
// The black square is the middle 8 x 8 cells (its side is Marker::size); the outer ring is white, and the
// paper should leave at least one more cell of white around it.
inline constexpr int kMarkerCells = 10;
std::vector<bool> markerCells(int id);

// One of the scene's markers found in a frame.
struct MarkerSighting {
    int marker = 0;                     // index into the scene's markers
    std::array<glm::dvec2, 4> corners;  // pixels (x right, y down, 0 at the top-left pixel's corner)
    float decisionMargin = 0.0f;        // the detector's confidence in the decoded bits
};

// Markers whose square is narrower than this in the image (its shortest side, pixels) are not trusted: their
// corners are too few pixels apart for a pose.
inline constexpr double kMinMarkerSidePx = 16.0;

// Finds the scene's markers in frames (grey levels from the frame's linear RGB).
class MarkerDetector {
  public:
    explicit MarkerDetector(std::span<const Marker> markers);
    ~MarkerDetector();
    MarkerDetector(const MarkerDetector&) = delete;
    MarkerDetector& operator=(const MarkerDetector&) = delete;

    struct Result {
        std::vector<MarkerSighting> sightings;  // the scene's markers, large enough to trust
        int unknown = 0;                        // tag36h11 tags that are not in the scene
        int tooSmall = 0;                       // the scene's markers seen under kMinMarkerSidePx
    };
    // The scene's markers in a frame. Large frames of a stream are searched at half resolution, at full
    // resolution too when that finds fewer markers than the frame before: one detector per stream.
    Result detect(const Image& frame);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// A camera pose solved from sightings.
struct MarkerPose {
    glm::mat4 worldFromCamera{1.0f};
    double reprojectionErrorPx = 0.0;  // RMS over every corner, through the lens distortion
    int markersSeen = 0;
    // Another pose, its camera elsewhere, explains the corners about as well (the planar ambiguity below):
    // the pose returned is the nearer to `previous`, or without one a guess.
    bool ambiguous = false;
    // The standard deviation of the camera's position (world units) were each corner 0.3 pixels off at
    // random, and at least the distance to the other pose when ambiguous: about 1 % of the distance to the
    // markers with two 10-12 cm markers 1 m away at 320x240, 15-30 % with one of them seen nearly head-on.
    double positionSigma = 0.0;
    double markerDistance = 0.0;  // from the camera to the largest marker seen (world units)
};

// The pose of `camera` (its intrinsics and distortion; its pose is ignored) that best explains the
// sightings; nothing when there is none or the solution is behind the camera or not finite. A marker seen
// nearly head-on has two poses that explain its corners almost equally well (tilted either way about the
// line of sight): where their errors are close, the one whose camera is nearer `previous` (the last frame's
// world-from-camera) is taken. With `previousSigma` (world units: how far the camera may have moved since
// `previous`) the pose is then refined with the camera's distance from the last one as a term of the error
// (a prior): one small marker alone, whose corners fit cameras tens of centimetres apart almost equally, then
// gives the pose near the last one that fits them.
std::optional<MarkerPose> solveCameraPose(std::span<const MarkerSighting> sightings,
                                          std::span<const Marker> markers, const Camera& camera,
                                          const std::optional<glm::mat4>& previous = std::nullopt,
                                          double previousSigma = 0.0);

// One-Euro filtering of a camera pose: position and orientation (a quaternion kept in one hemisphere) each
// low-passed with a cut-off that rises with their speed.
struct PoseSmoothing {
    double minCutoffHz = 1.0;    // the cut-off of a still camera: lower is steadier
    double positionBeta = 40.0;  // cut-off increase per world unit per second of camera speed
    double rotationBeta = 60.0;  // per radian per second
    double derivativeCutoffHz = 2.0;
    bool enabled = true;
};

class PoseFilter {
  public:
    explicit PoseFilter(PoseSmoothing smoothing = {}) : smoothing_(smoothing) {}
    // The filtered pose at `timeSeconds` (increasing; a time that does not increase restarts the filter).
    glm::mat4 filter(const glm::mat4& worldFromCamera, double timeSeconds);
    void reset() { started_ = false; }

  private:
    PoseSmoothing smoothing_;
    bool started_ = false;
    double lastTime_ = 0.0;
    glm::dvec3 position_{0.0}, positionSpeed_{0.0};
    glm::dvec4 rotation_{0.0}, rotationSpeed_{0.0};  // quaternion (x, y, z, w)
};

// Registration of a stream of frames: detect, solve, smooth, and hold the last pose for a while when the
// markers are lost.
struct TrackingOptions {
    PoseSmoothing smoothing;
    double holdSeconds = 0.5;  // how long the last pose stands in when no marker is seen
    // A pose from no more markers than the last registered frame's that would have moved the camera faster
    // than this (world units per second, metres in the examples; plus 1 cm) since that frame, within the
    // hold time, is not trusted: the frame is held. One small marker seen alone leaves the tilt uncertain,
    // and a little corner noise (a JPEG's) can put the camera tens of centimetres off for a frame or two. 0:
    // every pose is taken. The same speed times the time since the last registered frame is the width of the
    // prior a pose is refined with (solveCameraPose's previousSigma).
    double maxSpeed = 2.0;
    // A pose is certain when its position's standard deviation (MarkerPose::positionSigma) is at most this
    // share of the distance to the marker. A stream starts from a certain pose; an uncertain
    // one later is taken only when the prior holds it (solveCameraPose: the camera cannot have gone further
    // since the last registered frame than the corners are uncertain), else treated as no marker.
    double certainSigma = 0.05;
};

struct TrackedFrame {
    enum class State {
        Registered,  // the markers gave this frame's pose
        Held,        // no marker: the last pose, for up to holdSeconds
        Lost         // no marker for longer: no pose
    };
    State state = State::Lost;
    glm::mat4 worldFromCamera{1.0f};   // smoothed; meaningless when Lost
    double reprojectionErrorPx = 0.0;  // of the unsmoothed solution (Registered only)
    int markersSeen = 0;
    int unknownTags = 0, tooSmall = 0;
    bool jumped = false;  // Held because the markers' pose moved the camera faster than maxSpeed
    // No pose from this frame: the markers seen fit poses far apart (TrackingOptions::certainSigma) and no
    // earlier pose near enough in time chooses between them (one small marker alone; a second marker or a
    // nearer camera decides)
    bool uncertain = false;
};

class MarkerTracker {
  public:
    // `camera`: the scene camera's intrinsics and distortion, of the frames' size.
    MarkerTracker(std::span<const Marker> markers, const Camera& camera, TrackingOptions options = {});
    TrackedFrame track(const Image& frame, double timeSeconds);

  private:
    std::vector<Marker> markers_;
    Camera camera_;
    TrackingOptions options_;
    MarkerDetector detector_;
    PoseFilter filter_;
    std::optional<double> lastSeen_;
    glm::mat4 lastPose_{1.0f};  // smoothed
    glm::mat4 lastRaw_{1.0f};   // as solved
    int lastMarkersSeen_ = 0;
};

}  // namespace deltagi
