// `deltagi eval`: DGI and its baselines against the differential path tracer (see docs/ground-truth.md).
#include "evaluation/evaluation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/parallel.h"
#include "deltagi/error.h"
#include "deltagi/scene_io.h"
#include "reference/path_tracer.h"

namespace deltagi {

namespace {

constexpr int64_t kRowGrain = 4;

// a / b for norms: 0 when both are 0, infinity (null in JSON) when only the reference is 0.
double ratio(double a, double b) {
    if (b > 0.0) return a / b;
    return a > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
}

Scene withBackground(const Scene& scene, const Image& background) {
    Scene s = scene;  // copies meshes; an evaluation renders three times anyway
    s.background = background;
    return s;
}

}  // namespace

size_t PixelClasses::count(PixelClass c) const {
    return static_cast<size_t>(std::count(classes.begin(), classes.end(), c));
}

double directVisibility(const RayScene& occluders, std::span<const Light> lights, glm::vec3 position,
                        glm::vec3 normal, float rayOffset) {
    constexpr int k = 4;
    static_assert(k * k == kVisibilitySamplesPerLight);
    double unoccluded = 0.0, visible = 0.0;
    for (const Light& light : lights)
        for (int j = 0; j < k; ++j)
            for (int i = 0; i < k; ++i) {
                const LightSample s = sampleLightPoint(light, position, (j + 0.5f) / k, (i + 0.5f) / k);
                const float cosTheta = glm::dot(s.wi, normal);
                if (cosTheta <= 0.0f || s.irradiance == glm::vec3(0.0f)) continue;
                const double e = cosTheta * (s.irradiance.x + s.irradiance.y + s.irradiance.z);
                unoccluded += e;
                const glm::vec3 origin = position + rayOffset * normal;
                const float tMax = std::isfinite(s.distance) ? s.distance - 2.0f * rayOffset : s.distance;
                if (tMax > 0.0f && !occluders.intersect(origin, s.wi, 0.0f, tMax).hit()) visible += e;
            }
    return unoccluded > 0.0 ? visible / unoccluded : -1.0;
}

PixelClasses classifyPixels(const Scene& scene, const Image& dgiMask, const Image& referenceMask) {
    const Camera& camera = scene.camera;
    const RayScene all(scene, SceneContent::RealAndVirtual);
    const RayScene realOnly(scene, SceneContent::RealOnly);
    const float rayOffset =
        kRayOffsetScale * std::max(all.bounds().empty() ? 1.0f : all.bounds().maxExtent(), 1e-3f);
    PixelClasses out;
    out.width = camera.width;
    out.height = camera.height;
    out.classes.assign(static_cast<size_t>(out.width) * out.height, PixelClass::Edge);
    const glm::vec3 eye = camera.position();
    parallelFor(0, out.height, kRowGrain, [&](int64_t y64) {
        const int y = static_cast<int>(y64);
        for (int x = 0; x < out.width; ++x) {
            const size_t i = static_cast<size_t>(y) * out.width + x;
            const float a = dgiMask.at(x, y, 0), b = referenceMask.at(x, y, 0);
            if (a >= 1.0f && b >= 1.0f) {
                out.classes[i] = PixelClass::Object;
                continue;
            }
            if (a > 0.0f || b > 0.0f) continue;  // the silhouette
            // The real surface the pixel centre sees (as the pipeline's G-buffer); no surface: nothing is
            // lit.
            const glm::vec3 dir = glm::normalize(camera.rayDirection(x + 0.5f, y + 0.5f));
            const RayHit hit = realOnly.intersect(eye, dir);
            const double v =
                hit.hit() ? directVisibility(all, scene.lights, hit.position, hit.normal, rayOffset) : -1.0;
            out.classes[i] = v >= kLitVisibilityThreshold ? PixelClass::RealLit : PixelClass::RealShadowed;
        }
    });
    return out;
}

DeltaFigures deltaFigures(const Image& composite, const Image& reference, const Image& background,
                          const PixelClasses& classes) {
    double deltaError = 0.0, deltaRef = 0.0, objectError = 0.0, objectRef = 0.0, squared = 0.0;
    double biasSum[2] = {0.0, 0.0};
    size_t biasCount[2] = {0, 0};
    const int w = composite.width(), h = composite.height();
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::dvec3 test(composite.rgb(x, y)), ref(reference.rgb(x, y)), bg(background.rgb(x, y));
            const glm::dvec3 error = test - ref;  // = delta_test - delta_ref: the background is shared
            squared += glm::dot(error, error);
            switch (classes.classes[static_cast<size_t>(y) * w + x]) {
                case PixelClass::Object:
                    objectError += glm::dot(error, error);
                    objectRef += glm::dot(ref, ref);
                    break;
                case PixelClass::RealLit:
                case PixelClass::RealShadowed: {
                    const glm::dvec3 deltaReference = ref - bg;
                    deltaError += glm::dot(error, error);
                    deltaRef += glm::dot(deltaReference, deltaReference);
                    const int k =
                        classes.classes[static_cast<size_t>(y) * w + x] == PixelClass::RealLit ? 0 : 1;
                    biasSum[k] += (error.x + error.y + error.z) / 3.0;
                    ++biasCount[k];
                    break;
                }
                case PixelClass::Edge:
                    break;
            }
        }
    DeltaFigures f;
    f.deltaRelError = ratio(std::sqrt(deltaError), std::sqrt(deltaRef));
    f.objectRelRmse = ratio(std::sqrt(objectError), std::sqrt(objectRef));
    f.compositeRmse = w * h > 0 ? std::sqrt(squared / (3.0 * w * h)) : 0.0;
    f.biasLit = biasCount[0] ? biasSum[0] / static_cast<double>(biasCount[0]) : 0.0;
    f.biasShadowed = biasCount[1] ? biasSum[1] / static_cast<double>(biasCount[1]) : 0.0;
    return f;
}

Evaluation evaluate(const Scene& scene, const ReferenceOptions& referenceOptions,
                    const ReferenceProgress& onPass) {
    return evaluate(scene, renderReference(scene, referenceOptions, onPass));
}

Evaluation evaluate(const Scene& scene, ReferenceOutput reference) {
    for (const Image* image : {&reference.composite, &reference.background, &reference.objectMask})
        if (image->width() != scene.camera.width || image->height() != scene.camera.height)
            throw InputError("reference",
                             fmt::format("images are {}x{}, the scene's camera {}x{}", image->width(),
                                         image->height(), scene.camera.width, scene.camera.height));
    Evaluation e;
    e.reference = std::move(reference);
    e.referenceMs = e.reference.totalMs;
    const Image& background = e.reference.background;

    Scene dgiScene = withBackground(scene, background);
    e.dgiRender = render(dgiScene);
    e.dgiMs = e.dgiRender.totalMs;
    e.classes = classifyPixels(scene, e.dgiRender.objectMask, e.reference.objectMask);
    const Image& truth = e.reference.composite;
    e.dgi = deltaFigures(e.dgiRender.composite, truth, background, e.classes);

    // No relighting: the background on real pixels, DGI's object over it by coverage. On silhouette pixels
    // the object's own radiance is not available apart from the composite, so those blend background and
    // DGI's composite (their real part keeps a (1 - coverage) share of DGI's change).
    e.noRelightComposite = background;
    for (int y = 0; y < background.height(); ++y)
        for (int x = 0; x < background.width(); ++x) {
            const float c = e.dgiRender.objectMask.at(x, y, 0);
            e.noRelightComposite.setRgb(x, y,
                                        glm::mix(background.rgb(x, y), e.dgiRender.composite.rgb(x, y), c));
        }
    e.noRelight = deltaFigures(e.noRelightComposite, truth, background, e.classes);

    Scene shadowOnly = dgiScene;
    shadowOnly.options.render.relightIndirect = false;
    e.shadowOnlyComposite = render(shadowOnly).composite;
    e.shadowOnly = deltaFigures(e.shadowOnlyComposite, truth, background, e.classes);

    Scene singleVisibility = std::move(dgiScene);
    singleVisibility.options.render.doubleShadowFix = false;
    e.singleVisibility = deltaFigures(render(singleVisibility).composite, truth, background, e.classes);
    return e;
}

SequenceEvaluation evaluateSequence(Scene& scene, const ReferenceOptions& referenceOptions,
                                    const std::function<void(int, int)>& onFrame) {
    if (scene.sequence.empty()) throw InputError(scene.file.string(), "the scene has no \"sequence\"");
    const std::vector<SequenceFrame> frames = scene.sequence;
    const ShownFrame shown = shownFrame(scene);
    const int first = frames.front().index;
    std::vector<SequenceFrame> order = framesBeforeSequence(scene);
    order.insert(order.end(), frames.begin(), frames.end());
    FrameRenderer renderer;
    SequenceEvaluation out;
    for (const SequenceFrame& frame : order) {
        showFrame(scene, frame);
        if (frame.index < first) {
            renderer.render(scene);
            continue;
        }
        const ReferenceOutput reference = renderReference(scene, referenceOptions);
        // Over the photo, which is the reference's too; a frame without one over the reference's real scene,
        // as evaluate() renders a scene without a photo.
        if (!scene.background) scene.background = reference.background;
        const RenderOutput dgi = renderer.render(scene);
        const PixelClasses classes = classifyPixels(scene, dgi.objectMask, reference.objectMask);
        out.frames.push_back({frame.index,
                              deltaFigures(dgi.composite, reference.composite, *scene.background, classes),
                              dgi.totalMs, reference.totalMs});
        if (onFrame) onFrame(static_cast<int>(out.frames.size()), static_cast<int>(frames.size()));
    }
    const double n = static_cast<double>(out.frames.size());
    auto worstBySize = [](double& worst, double value) {
        if (std::abs(value) > std::abs(worst)) worst = value;
    };
    for (const SequenceFrameEvaluation& f : out.frames) {
        out.mean.deltaRelError += f.dgi.deltaRelError / n;
        out.mean.objectRelRmse += f.dgi.objectRelRmse / n;
        out.mean.compositeRmse += f.dgi.compositeRmse / n;
        out.mean.biasLit += f.dgi.biasLit / n;
        out.mean.biasShadowed += f.dgi.biasShadowed / n;
        out.worst.deltaRelError = std::max(out.worst.deltaRelError, f.dgi.deltaRelError);
        out.worst.objectRelRmse = std::max(out.worst.objectRelRmse, f.dgi.objectRelRmse);
        out.worst.compositeRmse = std::max(out.worst.compositeRmse, f.dgi.compositeRmse);
        worstBySize(out.worst.biasLit, f.dgi.biasLit);
        worstBySize(out.worst.biasShadowed, f.dgi.biasShadowed);
    }
    restoreShownFrame(scene, shown);
    return out;
}

nlohmann::ordered_json sequenceEvaluationToJson(const SequenceEvaluation& e, const Scene& scene) {
    nlohmann::ordered_json j;
    j["sequence"] = sequenceRangeText(scene);
    j["mean"] = figuresJson(e.mean);
    j["worst"] = figuresJson(e.worst);
    nlohmann::ordered_json frames = nlohmann::ordered_json::array();
    for (const SequenceFrameEvaluation& f : e.frames) {
        nlohmann::ordered_json frame = {{"index", f.index}};
        frame.update(figuresJson(f.dgi));
        frame["dgi_ms"] = f.dgiMs;
        frame["reference_ms"] = f.referenceMs;
        frames.push_back(std::move(frame));
    }
    j["frames"] = std::move(frames);
    return j;
}

nlohmann::ordered_json figuresJson(const DeltaFigures& f) {
    nlohmann::ordered_json j;
    j["delta_rel_error"] = f.deltaRelError;
    j["object_rel_rmse"] = f.objectRelRmse;
    j["composite_rmse"] = f.compositeRmse;
    j["bias_lit"] = f.biasLit;
    j["bias_shadowed"] = f.biasShadowed;
    return j;
}

nlohmann::ordered_json evaluationToJson(const Evaluation& e) {
    nlohmann::ordered_json j = figuresJson(e.dgi);
    j["baselines"] = {{"no_relight", figuresJson(e.noRelight)},
                      {"shadow_only", figuresJson(e.shadowOnly)},
                      {"single_visibility", figuresJson(e.singleVisibility)}};
    j["dgi_ms"] = e.dgiMs;
    j["reference_ms"] = e.referenceMs;
    return j;
}

}  // namespace deltagi
