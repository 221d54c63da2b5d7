#include "scene/option_table.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>

#include <fmt/format.h>

#include "deltagi/error.h"
#include "deltagi/scene_io.h"

namespace deltagi {

using nlohmann::json;

namespace {

// ---- the kinds of values ----------------------------------------------------------------------------------

// What an option of type T takes: its description in the docs, and how it is read and written.
template <typename T>
struct ValueKind {
    std::string type;
    std::function<T(const JsonNode&)> read;
    std::function<json(const T&)> write;
};

// "a, b or c".
std::string joinWithOr(const std::vector<std::string>& items) {
    std::string result;
    for (size_t i = 0; i < items.size(); ++i)
        result += (i == 0 ? "" : i + 1 == items.size() ? " or " : ", ") + items[i];
    return result;
}

// The integers an option takes: those in [lo, hi], or only the powers of two or the squares among them;
// "auto" too (`autoValue` here) where `orAuto`.
struct Integers {
    int lo, hi;
    enum class Only { All, PowersOfTwo, Squares } only = Only::All;
    bool orAuto = false;
    int autoValue = 0;  // outside [lo, hi]

    bool allows(int64_t v) const {
        if (v < lo || v > hi) return false;
        int64_t root = 0;
        switch (only) {
            case Only::All:
                return true;
            case Only::PowersOfTwo:
                return v > 0 && (v & (v - 1)) == 0;
            case Only::Squares:
                while (root * root < v) ++root;  // v <= hi: a few steps
                return root * root == v;
        }
        return false;
    }
    // "an integer in [1, 8]", "1, 4, 9 or 16 (a square grid)", "a power of two in [4, 1024]", with "auto" or
    // before it where that is allowed; for the docs without the article and with `"auto"` as code.
    std::string describe(bool docs) const {
        std::vector<std::string> listed;
        for (int v = std::max(lo, 1); only != Only::All && v <= hi && listed.size() <= kMaxListed; ++v)
            if (allows(v)) listed.push_back(std::to_string(v));
        std::string values;
        if (only == Only::All)
            values = fmt::format("{}integer in [{}, {}]", docs ? "" : "an ", lo, hi);
        else if (listed.size() > kMaxListed)
            values = fmt::format("{}a {} in [{}, {}]", docs ? "integer, " : "",
                                 only == Only::PowersOfTwo ? "power of two" : "square", lo, hi);
        else
            values = joinWithOr(listed) + (only == Only::Squares ? " (a square grid)" : "");
        return orAuto ? (docs ? "`\"auto\"` or " : "\"auto\" or ") + values : values;
    }

  private:
    static constexpr size_t kMaxListed = 6;  // more are "a power of two in [lo, hi]"
};

ValueKind<int> integers(Integers set) {
    return {set.describe(true),
            [set](const JsonNode& node) {
                if (set.orAuto && node.value().is_string()) {
                    if (node.string() != "auto")
                        node.fail(fmt::format("expected {}, got {}", set.describe(false),
                                              describeValue(node.value())));
                    return set.autoValue;
                }
                const int64_t v = node.integer64();
                if (!set.allows(v)) node.fail(fmt::format("expected {}, got {}", set.describe(false), v));
                return static_cast<int>(v);
            },
            [set](const int& v) { return set.orAuto && v == set.autoValue ? json("auto") : json(v); }};
}
ValueKind<int> integers(int lo, int hi) {
    return integers(Integers{lo, hi});
}
// A pixel stride: "auto" (0: pixelStrideFor) or a power of two up to 32.
const Integers kStrides{1, 32, Integers::Only::PowersOfTwo, true};

ValueKind<float> numbers(Interval range) {
    std::string type = std::isinf(range.hi) && !std::isinf(range.lo)
                           ? fmt::format("number {} {}", range.loOpen ? ">" : ">=", range.lo)
                           : "number in " + range.str();
    return {std::move(type), [range](const JsonNode& node) { return node.floatNumber(range); },
            [](const float& v) { return json(v); }};
}

// A number in `range` or "auto" (a negative number here).
ValueKind<float> numbersOrAuto(Interval range) {
    const ValueKind<float> number = numbers(range);
    return {"`\"auto\"` or " + number.type,
            [range, type = "\"auto\" or " + number.type](const JsonNode& node) {
                if (node.value().is_string()) {
                    if (node.string() != "auto")
                        node.fail(fmt::format("expected {}, got {}", type, describeValue(node.value())));
                    return -1.0f;
                }
                return node.floatNumber(range);
            },
            [](const float& v) { return v < 0.0f ? json("auto") : json(v); }};
}

ValueKind<bool> boolean() {
    return {"boolean", [](const JsonNode& node) { return node.boolean(); },
            [](const bool& v) { return json(v); }};
}

ValueKind<glm::vec3> point() {
    return {"[x, y, z]", [](const JsonNode& node) { return node.vec3(); },
            [](const glm::vec3& v) {
                return json::array({v.x, v.y, v.z});
            }};
}

// `kind`, or null for "not set" (so that what optionsToJson writes reads back).
template <typename T>
ValueKind<std::optional<T>> orNull(ValueKind<T> kind) {
    return {kind.type + " or `null`",
            [read = kind.read](const JsonNode& node) {
                return node.value().is_null() ? std::nullopt : std::optional<T>(read(node));
            },
            [write = kind.write](const std::optional<T>& v) { return v ? write(*v) : json(nullptr); }};
}

// One of the names in `table`.
template <typename Enum, size_t N>
ValueKind<Enum> names(const EnumName<Enum> (&table)[N]) {
    std::vector<std::string> quoted, code;
    for (const EnumName<Enum>& entry : table) {
        quoted.push_back(fmt::format("\"{}\"", entry.name));
        code.push_back(fmt::format("`\"{}\"`", entry.name));
    }
    return {joinWithOr(code),
            [&table, expected = joinWithOr(quoted)](const JsonNode& node) {
                const std::string name = node.string();
                for (const EnumName<Enum>& entry : table)
                    if (entry.name == name) return entry.value;
                node.fail(fmt::format("expected {}, got \"{}\"", expected, name));
            },
            [&table](const Enum& v) { return json(nameOf(table, v)); }};
}

// ---- options and groups -----------------------------------------------------------------------------------

// One option of a group of type G (RenderOptions), before it knows its group.
template <typename G>
struct Entry {
    std::string key, type, unit, defaultNote, doc;
    std::function<void(const JsonNode&, G&)> read;
    std::function<json(const G&)> write;

    Entry withDefaultNote(std::string note) && {
        defaultNote = std::move(note);
        return std::move(*this);
    }
};

template <typename G, typename T>
Entry<G> option(std::string key, T G::*member, ValueKind<T> kind, std::string unit, std::string doc) {
    return {
        std::move(key),
        std::move(kind.type),
        std::move(unit),
        {},
        std::move(doc),
        [member, read = std::move(kind.read)](const JsonNode& node, G& group) { group.*member = read(node); },
        [member, write = std::move(kind.write)](const G& group) { return write(group.*member); }};
}

template <typename G>
OptionGroup group(std::string name, G Options::*member, std::vector<Entry<G>> entries,
                  std::function<void(const JsonNode&, const Options&)> check = {}) {
    OptionGroup result{std::move(name), {}, std::move(check)};
    for (Entry<G>& e : entries)
        result.options.push_back(
            {result.name, std::move(e.key), std::move(e.type), std::move(e.unit), std::move(e.defaultNote),
             std::move(e.doc),
             [member, read = std::move(e.read)](const JsonNode& node, Options& o) { read(node, o.*member); },
             [member, write = std::move(e.write)](const Options& o) { return write(o.*member); }});
    return result;
}

// The "auto" stride of an option at 640x480, for the docs: `stride` for lights, `areaStride` for emitters and
// the environment map.
std::string autoStrideNote(int stride, int areaStride) {
    if (stride == areaStride) return fmt::format("{} at 640x480, for every kind of light", stride);
    return fmt::format("{} at 640x480 ({} for emitters and the environment map)", stride, areaStride);
}
// ... and `environmentStride` for the environment map.
std::string autoStrideNote(int stride, int areaStride, int environmentStride) {
    if (areaStride == environmentStride) return autoStrideNote(stride, areaStride);
    return fmt::format("{} at 640x480 ({} for emitters, {} for the environment map)", stride, areaStride,
                       environmentStride);
}
std::string autoStrideNote(int stride) {
    return fmt::format("{} at 640x480", stride);
}

constexpr Interval kAperture{0.0, 180.0, false, true};  // a full apex angle that may be 0 ("derived")
constexpr Interval kOpenAperture{0.0, 180.0, true, true};

// ---- the table --------------------------------------------------------------------------------------------

OptionGroup volumeGroup() {
    using V = VolumeOptions;
    return group(
        "volume", &Options::volume,
        {
            option("resolution", &V::resolution, integers({4, 1024, Integers::Only::PowersOfTwo}), "voxels",
                   "voxels along each axis"),
            option("extent_scale", &V::extentScale, numbers(kPositive), "× box",
                   "without an explicit region, the volumes cover this multiple of the virtual objects' "
                   "bounding box (the real scene's when there are no virtual objects), made cubic around its "
                   "centre"),
            option(
                "reach_scale", &V::reachScale, numbers({0.0, 1024.0}), "× box",
                "without an explicit region, the cube grows from `extent_scale` up to this multiple of the "
                "objects' box to take in the real surfaces around them, and is moved (keeping the objects "
                "inside) to hold as much of the real scene as it can: the walls and floor that light the "
                "object and receive its shadow and light. 0 keeps the paper's `extent_scale` cube (§3.4), "
                "which stops short of the floor under a hanging object, whose lower half then gets no light "
                "([design.md](design.md#departures-from-the-paper))"),
            option("center", &V::center, orNull(point()), "world units",
                   "centre of an explicit cubic region, world space"),
            option("size", &V::size, orNull(numbers(kPositive)), "world units",
                   "edge length of the explicit region. `center` and `size` are given both or neither"),
            option(
                "viewpoint", &V::viewpoint, orNull(point()), "world units",
                "the point that says which side of a real surface is the room's: surfaces are two-sided and "
                "a reconstruction's winding is not reliable, so the reflective shadow maps of directional "
                "lights (the environment's among them), which come from outside, keep a real surface's "
                "texels where its lit side faces this point, and the further bounces gather on its side "
                "(a point or spot light stands in the room: its maps keep every texel). A fixed point lets "
                "the camera move without the real scene's volumes being redone "
                "(`FrameRenderer`); with the camera's position they are kept while the camera stays on the "
                "same side of every real surface")
                .withDefaultNote(
                    "the camera's position; with a `sequence`, its transforms file's first camera"),
        },
        [](const JsonNode& node, const Options& o) {
            if (o.volume.center.has_value() == o.volume.size.has_value()) return;
            if (o.volume.center)
                node.child("center").fail("given without options.volume.size; give both or neither");
            node.child("size").fail("given without options.volume.center; give both or neither");
        });
}

OptionGroup rsmGroup() {
    const std::string doc = fmt::format(
        "texels along each side of one shadow-map face (up to 6 faces, 48 bytes per texel, two maps per "
        "light: the scene's and its update with the objects). `\"auto\"`: a point or spot light's maps have "
        "{} texels per voxel along the volume's side, in [{}, {}] ({} at 256³ and above, {} at 128³, {} at "
        "64³, {} at 32³), a directional light's {} per voxel, in [{}, {}] ({} at 128³ and below, {} at 256³: "
        "its orthographic map spreads over the whole region); with several lights, each takes the square "
        "root of its share of the brightest light's irradiance in the volume (its largest over the region's "
        "centre and corners) times that, to the nearest power of two, at least 1/{} of it. Figures: "
        "[design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays), "
        "[performance.md](performance.md#many-lights)",
        kAutoRsmTexelsPerVoxel, kAutoRsmMinResolution, kAutoRsmMaxResolution,
        rsmResolutionCeiling(0, 256, false), rsmResolutionCeiling(0, 128, false),
        rsmResolutionCeiling(0, 64, false), rsmResolutionCeiling(0, 32, false),
        kAutoRsmDirectionalTexelsPerVoxel, kAutoRsmDirectionalMinResolution, kAutoRsmMaxResolution,
        rsmResolutionCeiling(0, 128, true), rsmResolutionCeiling(0, 256, true), kAutoRsmMinShare);
    return group("rsm", &Options::rsm,
                 {option("resolution", &RsmOptions::resolution,
                         integers({16, 8192, Integers::Only::All, true}), "texels", doc)});
}

OptionGroup diffuseGroup() {
    using D = DiffuseConeOptions;
    return group(
        "diffuse", &Options::diffuse,
        {
            option("count", &D::count, integers(1, 64), "cones",
                   "cones covering the hemisphere, cosine weighted"),
            option(
                "aperture_deg", &D::apertureDeg, numbers(kAperture), "degrees",
                "full apex angle of each cone; 0 derives it from `count` so that the cones' solid angles add "
                "up to the hemisphere (half-angle `acos(1 - 1/count)`: 54° for 9 cones)"),
            option(
                "object_aperture_deg", &D::objectApertureDeg, numbers(kAperture), "degrees",
                "the same for the virtual objects' own diffuse cones (0 derives it from `count`). Narrower "
                "cones that leave gaps between them: a wide cone reads coarse voxels a few steps from the "
                "surface, which blurs the objects' self-occlusion and the colours of the walls they see. The "
                "real surfaces' relit cones keep `aperture_deg` "
                "([design.md](design.md#departures-from-the-paper))"),
            option(
                "pixel_stride", &D::pixelStride, integers(kStrides), "pixels",
                fmt::format(
                    "trace the diffuse cones of rendered surfaces (the virtual objects; the real scene when "
                    "there is no photo) at every `pixel_stride`-th pixel of every `pixel_stride`-th row; the "
                    "edge-aware filter (`options.render.denoise_radius` samples around each pixel, spaced "
                    "`pixel_stride` apart) fills the others from traced samples on the same surface, and "
                    "pixels with none (thin parts, silhouettes) are traced as well. `\"auto\"` scales the "
                    "640x480 stride with the image's smaller side (÷ 480) and rounds it down to a power of "
                    "two, at least 1: a 64x48 image takes a stride of {}, 1280x960 one of {}",
                    pixelStrideFor(0, kAutoDiffuseStride, 64, 48),
                    pixelStrideFor(0, kAutoDiffuseStride, 1280, 960)))
                .withDefaultNote(fmt::format("{} at 640x480 for cones, {} for the objects' rays "
                                             "(`object_gather_rays`); {} for a single render's with "
                                             "`object_gather_rays` \"auto\"",
                                             kAutoDiffuseStride, kAutoDiffuseRayStride,
                                             kAutoStillDiffuseRayStride)),
            option(
                "relight_pixel_stride", &D::relightPixelStride, integers(kStrides), "pixels",
                "the same for the real surfaces' change (relighting): the light the objects add or take away "
                "varies slowly ([design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays))")
                .withDefaultNote(autoStrideNote(kAutoRelightDiffuseStride)),
            option(
                "object_rays", &D::objectRays, integers(0, 256), "rays",
                "rays (rounded down to a square number) that each coarse voxel of the virtual objects casts "
                "to gather the light they reflect once more (`options.render.light_bounces` ≥ 2), and that "
                "each relit real point casts towards the objects with `options.render.relight_object_light` "
                "`\"rays\"`. A ray takes the light volume's radiance at the level-0 voxels where it ends. "
                "The cones of a coarse voxel start half a voxel and more off its surface: under an object "
                "standing on the floor they start below the floor, and the object's underside got none of "
                "the floor's light (tested: a box on a lit floor gets albedo × the floor's radiance "
                "underneath by rays, under half of it by cones). 0: cones"),
            option("object_ray_pixel_stride", &D::objectRayPixelStride, integers(kStrides), "pixels",
                   "with `options.render.relight_object_light` `\"rays\"`: cast the relit points' rays "
                   "towards the objects at every `object_ray_pixel_stride`-th pixel of every such row and "
                   "interpolate the others like the diffuse cones' "
                   "([design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays))")
                .withDefaultNote(autoStrideNote(kAutoObjectRayStride)),
            option(
                "object_gather_rays", &D::objectGatherRays,
                integers(Integers{0, 256, Integers::Only::All, true, -1}), "rays",
                fmt::format(
                    "rays (rounded down to a square number) that each traced pixel of the virtual objects "
                    "casts over its hemisphere for its diffuse light instead of the cones: each takes the "
                    "light volume's radiance where it meets a surface, averaged over its share of the "
                    "hemisphere there (the mip level as wide). The cones read far surfaces through voxels "
                    "that hold their surroundings too: under a bare bulb near the Cornell box's ceiling they "
                    "bring a ball 66-78 % of the first bounce's light, rays 98 % of the first two "
                    "([design.md](design.md#departures-from-the-paper)). `\"auto\"`: {} for a single render "
                    "(a still, traced at every pixel: `pixel_stride` \"auto\"), {} for the frames of a "
                    "session (`serve`, `live`, `bench`, a `\"sequence\"`), which keep their time "
                    "([quality-notes.md](quality-notes.md)). 0: the diffuse cones of §3.1 (`count`, "
                    "`object_aperture_deg`)",
                    kAutoStillObjectGatherRays, kAutoObjectGatherRays)),
        });
}

OptionGroup specularGroup() {
    using S = SpecularConeOptions;
    return group(
        "specular", &Options::specular,
        {
            option("min_aperture_deg", &S::minApertureDeg, numbers(kOpenAperture), "degrees",
                   "the aperture derived from a material's roughness is clamped to [min, max] (full apex "
                   "angle); at most `max_aperture_deg`. Narrow cones take many small steps"),
            option("max_aperture_deg", &S::maxApertureDeg, numbers(kOpenAperture), "degrees",
                   "the upper end of that range"),
            option("relight_pixel_stride", &S::relightPixelStride, integers(kStrides), "pixels",
                   "trace the real surfaces' change through specular cones (the objects seen in glossy real "
                   "surfaces) at every `relight_pixel_stride`-th pixel of every such row and interpolate the "
                   "others like the diffuse cones'; the virtual objects' own reflections are traced at every "
                   "pixel ([design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays))")
                .withDefaultNote(autoStrideNote(kAutoRelightSpecularStride)),
        },
        [](const JsonNode& node, const Options& o) {
            if (o.specular.minApertureDeg > o.specular.maxApertureDeg)
                throw InputError(node.childWhere("min_aperture_deg"),
                                 fmt::format("expected at most max_aperture_deg ({}), got {}",
                                             o.specular.maxApertureDeg, o.specular.minApertureDeg));
        });
}

OptionGroup shadowGroup() {
    using S = ShadowConeOptions;
    const Options defaults;
    const int filterSide = 2 * defaults.render.denoiseRadius + 1;
    const int relitFilterSide = 2 * defaults.render.relightDenoiseRadius + 1;
    return group(
        "shadow", &Options::shadow,
        {
            option(
                "method", &S::method, names(kShadowMethodNames), "",
                "`\"rays\"`: shadow rays from each point towards `ray_samples` points spread over the light "
                "(a sphere light's disk facing the point, the cone of directions of an environment map's "
                "light), against the real scene's and the objects' triangles, filtered like the cones. "
                "`\"cones\"`: the paper's shadow cone through the visibility volumes (an occluder smaller "
                "than a coarse voxel fills it: shadows come out too wide and too dark, and they end at the "
                "volumes' faces). Figures of both: [design.md](design.md#departures-from-the-paper)"),
            option("ray_samples", &S::raySamples, integers(1, 256), "rays",
                   fmt::format(
                       "shadow rays per point and light with a size, on a jittered square grid (rounded down "
                       "to a square number); a light without a size takes one ray (a hard shadow, as in the "
                       "path tracer). The filter averages {0}×{0} traced pixels, so {1} give {2} rays per "
                       "pixel ([design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays))",
                       filterSide, defaults.shadow.raySamples,
                       filterSide * filterSide * defaults.shadow.raySamples)),
            option(
                "area_ray_samples", &S::areaRaySamples, integers(1, 256), "rays",
                "rays per point towards the emitting surfaces and towards the environment map, which sample "
                "many directions each, on a jittered square grid "
                "([design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays))"),
            option("aperture_deg", &S::apertureDeg, numbers({0.0, 90.0, true, false}), "degrees",
                   "cones only: full apex angle of the shadow cone of a light without a `radius` (one with a "
                   "radius r at distance d takes 2 atan(r/d))"),
            option(
                "pixel_stride", &S::pixelStride, integers(kStrides), "pixels",
                "trace the shadows of rendered surfaces at every `pixel_stride`-th pixel of every "
                "`pixel_stride`-th row and interpolate the others like `options.diffuse.pixel_stride`. With "
                "rays, 1 gives the objects' self-shadowing detail "
                "([design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays)); emitters and the "
                "environment map, sampled with more rays of more noise, take a stride of their own unless "
                "given")
                .withDefaultNote(autoStrideNote(kAutoShadowStride, kAutoAreaLightStride)),
            option(
                "relight_pixel_stride", &S::relightPixelStride, integers(kStrides), "pixels",
                fmt::format(
                    "the same for the shadows the objects cast on real surfaces: the filter spreads "
                    "{0}×{0} samples `relight_pixel_stride` apart (`options.render.relight_denoise_radius`), "
                    "and a contact shadow is sharper than that; a sky's is softer "
                    "([design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays))",
                    relitFilterSide))
                .withDefaultNote(autoStrideNote(kAutoRelightShadowStride, kAutoRelightAreaLightStride,
                                                kAutoRelightEnvironmentStride)),
        });
}

OptionGroup traceGroup() {
    using T = TraceOptions;
    return group(
        "trace", &Options::trace,
        {
            option("step_scale", &T::stepScale, numbers({0.05, 4.0}), "× cone diameter",
                   "distance between samples as a fraction of the cone diameter there"),
            option("start_offset", &T::startOffset, numbers({0.0, 16.0}), "voxels",
                   "the cone starts this many voxels (level-0 voxel edges) away from the surface, along the "
                   "normal and the cone's axis, so that a surface does not occlude itself"),
            option("max_occlusion", &T::maxOcclusion, numbers({0.5, 1.0}), "",
                   "a cone stops once its accumulated occlusion reaches this value"),
            option(
                "normal_weight", &T::normalWeight, numbers(kUnit), "",
                "how strongly a voxel's average normal adapts its occlusion (§3.1): 0 isotropic, 1 a voxel "
                "whose normals agree occludes a grazing cone in proportion to the cosine"),
            option("backface_weight", &T::backfaceWeight, numbers(kUnit), "",
                   "how much less a voxel occludes a cone that leaves it through the back of its surface: 0 "
                   "two-sided, 1 a coherent back face does not occlude (prevents the shadow terminator on "
                   "convex surfaces)"),
            option("jitter", &T::jitter, numbers(kUnit), "× step",
                   "each cone's first step is offset by this fraction of a step, random per pixel (seeded by "
                   "the pixel index): turns banding into fine noise. 0 disables it"),
            option("accumulation", &T::accumulation, names(kConeAccumulationNames), "",
                   "`\"paper\"`: the accumulator formulas of §3.1 as printed (light = light·occ + "
                   "light_local·occ_local·(1 − occ)); `\"front_to_back\"`: usual emission-absorption "
                   "compositing (light += light_local·occ_local·(1 − occ))"),
        });
}

OptionGroup renderGroup() {
    using R = RenderOptions;
    return group(
        "render", &Options::render,
        {
            option(
                "layers", &R::layers, boolean(), "",
                "also make the compositing layers (object, shadow, indirect, depth; "
                "[command-line.md](command-line.md#compositing-layers)); `deltagi render --layers` sets it. "
                "Off by default: four more images a frame"),
            option(
                "samples_per_pixel", &R::samplesPerPixel, integers({1, 16, Integers::Only::Squares}),
                "samples",
                "sub-pixel samples of the G-buffer; the object mask is their coverage, and the objects' "
                "direct light is the mean over them: each pixel of an object keeps the surfaces of its "
                "sub-samples, its shadow rays start from them in turn (at least one each, counted by their "
                "cosine), and its unshadowed light is their mean. A fold or a shadow edge inside a pixel "
                "then shows as the path tracer shows it, not as the light at the pixel's centre "
                "([design.md](design.md#departures-from-the-paper)). 1: one point per pixel (and no "
                "anti-aliased silhouette); 4 costs 4 camera rays per object pixel"),
            option("indirect", &R::indirect, boolean(), "",
                   "trace the diffuse and specular cones; `false`: direct light and shadow cones only"),
            option(
                "double_shadow_fix", &R::doubleShadowFix, boolean(), "",
                "relight real surfaces with the object's shadow only where the real scene does not already "
                "shadow them (§3.2); `false` reproduces the double shadow"),
            option(
                "denoise_radius", &R::denoiseRadius, integers(0, 8), "pixels",
                "pixels of the edge-aware filter over the shadow and diffuse cone results (it averages the "
                "noise of the jittered cone starts, `options.trace.jitter`) on the rendered surfaces (the "
                "virtual objects; the real scene when there is no photo); 0 disables it"),
            option(
                "relight_denoise_radius", &R::relightDenoiseRadius, integers(0, 8), "samples",
                "the same filter over the real surfaces' change (the relit shadow, diffuse, objects' light "
                "and specular passes), in samples of each pass's stride (at least 1 "
                "where the stride is over 1: the pixels between samples are interpolated). 1, the "
                "3×3 samples around each, keeps a contact shadow's core and the objects' light next to "
                "them: 2 spread them over 5×5 samples, 40 pixels at the objects' light's stride of 8 "
                "(quality suite: every delta_rel_error lower with 1). 2 gives steadier frames: the noise "
                "of the objects' light by rays, averaged over fewer samples, flickers about a quarter more "
                "with 1 ([quality-notes.md](quality-notes.md#stable-frames))"),
            option(
                "refine_budget", &R::refineBudget, numbersOrAuto({0.0, 0.25}), "of the pixels",
                "the relit passes of the environment map's light and of the objects' light by rays trace "
                "their samples sparsely (`options.shadow.relight_pixel_stride`, "
                "`options.diffuse.object_ray_pixel_stride`) and interpolate between them; where the samples "
                "around a cell differ by more than a tenth of the pass's largest value (a contact shadow's "
                "core, the objects' glow at their feet, a silhouette), the sharpest cells are traced again "
                "at a quarter of the stride, up to this share of the image's pixels a pass. `\"auto\"`: "
                "0.01 for a single render, 0 for the frames of a session (`serve`, `live`, `bench`, a "
                "`\"sequence\"`), which keep their time. 0 turns it off "
                "([design.md](design.md#sparse-tracing-the-strides-and-the-shadow-rays))"),
            option(
                "temporal_frames", &R::temporalFrames, integers(1, 8), "frames",
                "frames of a sequence (`deltagi render` over a `\"sequence\"`, `stability`, `bench`, "
                "`serve`, Python's `FrameRenderer`) that each pixel's objects' radiance and real surfaces' "
                "change of direct light (the shadows) are averaged over: its own and those of the frames "
                "before it, found again by reprojection (a real point where it was, an object's point on its "
                "triangle) and clamped to the range of the frame's own 3×3 neighbourhood, so a moving shadow "
                "does not leave a trail (`src/pipeline/temporal_reuse.*`). A window, not a running average: "
                "once the objects and the camera stop, the `temporal_frames`-th frame is the frame without "
                "reuse; a "
                "range of frames (`--frames A:B`) renders the `temporal_frames − 1` frames before A first, "
                "unwritten. 1 turns it off. A single `render` has no frames before it "
                "([design.md](design.md#temporal-reuse); what it buys: "
                "[quality-notes.md](quality-notes.md#stable-frames))"),
            option("relight_indirect", &R::relightIndirect, boolean(), "",
                   "add the indirect change (cones in the delta volume) to real surfaces; `false` keeps only "
                   "the object's shadow there (the object itself is still shaded in full)"),
            option(
                "light_bounces", &R::lightBounces, integers(1, 8), "bounces",
                "bounces of indirect light the light volumes carry. 1 is the paper: the reflective shadow "
                "maps inject the directly lit surfaces and the cones gather one bounce. Each more gathers "
                "the volume at every surface voxel of the real scene (over 16^3 voxels, with `bounce_rays` "
                "rays or `bounce_cones` cones, on the side facing the camera) and adds what it reflects, "
                "once "
                "while the real side stays the same (`src/pipeline/bounce_light.*`); the objects get the "
                "room's bounced light, and their own voxels gather the full volume every frame (at a quarter "
                "of the volume's resolution) and add what they reflect. 3: the bounces after the second are "
                "estimated from the first two (`bounce_tail`), where one alone misjudged them "
                "([design.md](design.md#departures-from-the-paper), with its cost)"),
            option(
                "bounce_tail", &R::bounceTail, boolean(), "",
                "add the bounces beyond `light_bounces` as a geometric series of the last one: its light "
                "times r / (1 - r), where r is the ratio of the last bounce's light to the one before's over "
                "the real scene's surfaces (per colour channel, at most 0.8). In a closed room the further "
                "bounces are as much light as the last one gathered (Cornell box under a bare bulb: the "
                "ball's object_rel_rmse 0.163 -> 0.088, with the objects' rays); an open scene gets almost "
                "none "
                "([design.md](design.md#departures-from-the-paper)). `false`: `light_bounces` bounces only"),
            option(
                "bounce_cones", &R::bounceCones, integers(1, 64), "cones",
                "cones each voxel gathers a further bounce with (the real scene's over 16^3 voxels, the "
                "objects' at a quarter of the volume's resolution), covering the hemisphere like "
                "`options.diffuse.count`. The bounce is smooth: 5 against the diffuse cones' 9 moves every "
                "quality-suite figure by at most 0.003 for half the gather's time "
                "([design.md](design.md#departures-from-the-paper)). Only with `bounce_rays` 0 for the "
                "real scene's voxels"),
            option(
                "bounce_rays", &R::bounceRays, integers(0, 256), "rays",
                "rays (rounded down to a square number) that each voxel of the real scene casts over its "
                "hemisphere to gather a further bounce, from the surface it holds on the camera's side; each "
                "takes the light of the level-0 voxels where it lands. Wide cones read far surfaces through "
                "coarse voxels that average them with their surroundings: under a bare bulb 10 cm below the "
                "Cornell box's ceiling they gather a fifth of the bright ceiling's light on the floor "
                "beneath, rays all of it ([design.md](design.md#departures-from-the-paper)). 0: the cones "
                "(`bounce_cones`)"),
            option(
                "relight_cones", &R::relightCones, names(kRelightConesNames), "",
                "how the real surfaces' indirect change is traced. `\"differential\"`: the full light volume "
                "through both visibility volumes (the scene's surfaces and the objects' each with their own "
                "radiance) minus the scene's own light through the scene's visibility alone, which holds the "
                "light the objects block between two real surfaces. `\"delta_volume\"`: the paper's delta "
                "volume through both visibility volumes (§3.3), which misses that blocked light "
                "([design.md](design.md#departures-from-the-paper))"),
            option(
                "relight_object_light", &R::relightObjectLight, names(kRelightObjectLightNames), "",
                "with `\"differential\"` relit cones, how the objects' own light, and the real light they "
                "hide, reach the real surfaces. `\"rays\"`: `options.diffuse.object_rays` rays from every "
                "`options.diffuse.object_ray_pixel_stride`-th relit pixel towards the objects' bounding "
                "sphere; where one meets an object it brings the objects' voxel radiance there and takes "
                "away the real scene's light it met before (the full minus the delta volume where the ray, "
                "continued through the objects, meets a real surface; `src/pipeline/object_bounce_rays.*`, "
                "tested against a bright sphere's solid angle and a sphere hiding a bright ceiling); the "
                "cones then carry only the change of the real surfaces' own light (the objects' shadows on "
                "them) through the real scene's visibility. `\"cones\"`: all of it through the cones, where "
                "a coarse voxel that holds an object and the floor under it hides the object from afar and "
                "spreads it wide nearby: under a bare bulb near the ceiling, the bright ceiling's light that "
                "a ball hides from the floor beneath it comes out at a third, and the ball's glow on the far "
                "walls and ceiling with the wrong sign ([design.md](design.md#departures-from-the-paper))"),
        });
}

OptionGroup environmentGroup() {
    using E = EnvironmentOptions;
    return group(
        "environment", &Options::environment,
        {
            option("light_count", &E::lightCount, integers(0, 256), "lights",
                   "directional lights extracted from the map; together they carry exactly the map's light "
                   "(solid-angle weighted). They drive the reflective shadow maps (and the shadow cones). 0 "
                   "leaves all of it to the sky term"),
            option("extraction", &E::extraction, names(kExtractionMethodNames), "",
                   "Debevec 2005: each region is split across its longest side (measured on the sphere) into "
                   "halves of equal energy; Viriyothai & Debevec 2009: at the cut that minimizes the "
                   "energy-weighted angular variance of the two halves. Each round splits every region; when "
                   "`light_count` is not a power of two the last round splits the most energetic ones"),
            option("sky", &E::sky, boolean(), "",
                   "with `shadow.method` `\"cones\"`: the sky term through the diffuse and specular cones "
                   "that leave the volumes (the map minus the extracted lights, prefiltered to their "
                   "aperture). `false`: the extracted lights only. With `\"rays\"` the whole map, sky "
                   "included, is traced by rays and this has no effect"),
            option(
                "max_light_aperture_deg", &E::maxLightApertureDeg, numbers(kOpenAperture), "degrees",
                "an extracted light's shadow cone is as wide as its region of the map (full apex angle), at "
                "most this"),
        });
}

}  // namespace

const std::vector<OptionGroup>& optionTable() {
    static const std::vector<OptionGroup> table = {volumeGroup(),   rsmGroup(),        diffuseGroup(),
                                                   specularGroup(), shadowGroup(),     traceGroup(),
                                                   renderGroup(),   environmentGroup()};
    return table;
}

Options readOptions(const JsonNode& node) {
    const std::vector<OptionGroup>& table = optionTable();
    std::vector<std::string_view> groups;
    for (const OptionGroup& group : table) groups.push_back(group.name);
    node.allowKeys(groups);
    Options options;
    for (const OptionGroup& group : table) {
        const std::optional<JsonNode> groupNode = node.find(group.name);
        if (!groupNode) continue;
        std::vector<std::string_view> keys;
        for (const OptionInfo& option : group.options) keys.push_back(option.key);
        groupNode->allowKeys(keys);
        for (const OptionInfo& option : group.options)
            if (const std::optional<JsonNode> value = groupNode->find(option.key))
                option.read(*value, options);
        if (group.check) group.check(*groupNode, options);
    }
    return options;
}

json optionsToJson(const Options& options) {
    json result = json::object();
    for (const OptionGroup& group : optionTable()) {
        json& object = result[group.name] = json::object();
        for (const OptionInfo& option : group.options) object[option.key] = option.write(options);
    }
    return result;
}

}  // namespace deltagi
