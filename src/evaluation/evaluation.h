// How close DGI is to the ground truth: image metrics (`deltagi compare`) and the evaluation of a scene
// against the differential path tracer (`deltagi eval`), with the baselines that show what each part of the
// method buys.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/ray_scene.h"
#include "deltagi/image.h"
#include "deltagi/reference.h"
#include "deltagi/renderer.h"
#include "deltagi/scene.h"

namespace deltagi {

// ---- Image metrics ----

// relMSE divides each squared error by reference^2 + this (Rousselle et al. 2011): dark pixels do not
// dominate.
constexpr double kRelMseEpsilon = 1e-2;

struct ImageMetrics {
    double rmse = 0.0;    // sqrt(mean((test - reference)^2)) over all pixels and channels
    double relMse = 0.0;  // mean((test - reference)^2 / (reference^2 + kRelMseEpsilon))
    double mae = 0.0;     // mean(|test - reference|)
};

// Compares two images of the same size (RGB, or 1 channel repeated). Throws InputError when sizes differ.
ImageMetrics compareImages(const Image& test, const Image& reference);

// Per pixel, 2 (reference - test)^2 averaged over the RGB channels: the quantity of the paper's Fig. 3c.
Image squaredDifference(const Image& test, const Image& reference);
// A value image (1 channel) in false colour: 0 black, through purple, orange, to `maxValue` and above pale
// yellow (an "inferno"-like ramp, readable in print). Returns an RGB image in linear space.
Image falseColour(const Image& values, float maxValue);
// A scale for falseColour that is not set by a few outliers: the 99th percentile of the values (at least a
// tiny positive number).
float robustMaximum(const Image& values);

// ---- Evaluation against the path-traced reference ----

// What each pixel counts for. Real pixels show no virtual object in either render; object pixels are fully
// covered in both; the silhouette's mixed pixels count only in composite_rmse.
enum class PixelClass : uint8_t { Edge, Object, RealLit, RealShadowed };

// A real pixel is lit when, at the real surface its centre sees, at least this fraction of the light's
// unoccluded direct irradiance arrives in the scene with the objects (light visibility, sampled over sphere
// lights' disks); shadowed otherwise, including surfaces a light does not reach at all.
constexpr double kLitVisibilityThreshold = 0.5;

struct PixelClasses {
    int width = 0, height = 0;
    std::vector<PixelClass> classes;  // row-major
    size_t count(PixelClass c) const;
};

struct DeltaFigures {
    // ||delta_test - delta_ref|| / ||delta_ref|| over real pixels (all channels), delta = composite -
    // background
    double deltaRelError = 0.0;
    // ||test - ref|| / ||ref|| over object pixels: the RMSE relative to the reference's RMS value
    double objectRelRmse = 0.0;
    double compositeRmse = 0.0;  // RMSE over all pixels and channels
    // Mean over pixels of the channel mean of delta_test - delta_ref, in lit and in shadowed real pixels:
    // negative means too much light is subtracted (or too little added).
    double biasLit = 0.0;
    double biasShadowed = 0.0;
};

// `background` is the image both composites were made over.
DeltaFigures deltaFigures(const Image& composite, const Image& reference, const Image& background,
                          const PixelClasses& classes);

struct Evaluation {
    DeltaFigures dgi;
    DeltaFigures noRelight;         // Δ = 0 on real pixels: the object pasted in
    DeltaFigures shadowOnly;        // options.render.relight_indirect = false
    DeltaFigures singleVisibility;  // options.render.double_shadow_fix = false (the double shadow)
    double dgiMs = 0.0;             // the DGI render, background given
    double referenceMs = 0.0;       // the path tracer, both renders
    PixelClasses classes;
    ReferenceOutput reference;
    RenderOutput dgiRender;  // background = reference.background
    Image noRelightComposite;
    Image shadowOnlyComposite;  // the quality suite splits DGI's change into its shadow and indirect parts
};

// Renders the reference first, then DGI and its baselines over the same background: the scene's photo, or the
// path-traced real scene (`without`) when it has none, so that the comparison of Δ isolates the relighting
// and is not blurred by how DGI would render the empty scene.
Evaluation evaluate(const Scene& scene, const ReferenceOptions& referenceOptions,
                    const ReferenceProgress& onPass = {});
// The same against a reference rendered before (`deltagi reference --aov` or `deltagi eval --aov`), so that
// many DGI settings can be judged against one ground truth. Throws InputError when its images do not match
// the scene's camera.
Evaluation evaluate(const Scene& scene, ReferenceOutput reference);

// A scene's tracked sequence ("sequence") scored frame by frame: each frame's reference rendered over its
// photo with its camera and keyframed objects, and DGI's frames as `deltagi render` gives them (one
// FrameRenderer over the frames in order, after the temporal_frames - 1 frames of the transforms file
// before the first, unscored), so that temporal reuse counts as it does in the frames a user gets.
struct SequenceFrameEvaluation {
    int index = 0;  // the frame's place in the transforms file
    DeltaFigures dgi;
    double dgiMs = 0.0, referenceMs = 0.0;
};
struct SequenceEvaluation {
    std::vector<SequenceFrameEvaluation> frames;
    DeltaFigures mean, worst;  // over the frames (worst: the largest of each figure, the biases' by size)
};
// `onFrame(done, total)` after each scored frame. The scene's camera, photo and objects are put back.
SequenceEvaluation evaluateSequence(Scene& scene, const ReferenceOptions& referenceOptions,
                                    const std::function<void(int, int)>& onFrame = {});
// {"sequence": "frames A:B of FILE", "mean": figures, "worst": figures, "frames": [{"index", figures...,
// "dgi_ms", "reference_ms"}]}.
nlohmann::ordered_json sequenceEvaluationToJson(const SequenceEvaluation& evaluation, const Scene& scene);

// One method's figures, with the keys of `deltagi eval --json`.
nlohmann::ordered_json figuresJson(const DeltaFigures& figures);

// The figures with exactly the keys of `deltagi eval --json` (see docs/ground-truth.md).
nlohmann::ordered_json evaluationToJson(const Evaluation& evaluation);

// ---- Internals, for the tests ----

// Light samples per light (a square grid over the sphere light's disk) for the lit/shadowed decision.
constexpr int kVisibilitySamplesPerLight = 16;

// Fraction of the unoccluded direct irradiance at `position` (normal `normal`) that arrives past `occluders`;
// -1 where no light reaches the point at all (facing away, outside every spot cone).
double directVisibility(const RayScene& occluders, std::span<const Light> lights, glm::vec3 position,
                        glm::vec3 normal, float rayOffset);

// Real, object and silhouette pixels from the two coverage masks (1 channel each), and lit vs shadowed real
// pixels by directVisibility() in the scene with the objects.
PixelClasses classifyPixels(const Scene& scene, const Image& dgiMask, const Image& referenceMask);

}  // namespace deltagi
