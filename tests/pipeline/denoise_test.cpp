#include "pipeline/denoise.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "pipeline/cone_trace.h"

namespace deltagi {
namespace {

// A point of `material` seen from +z.
SurfacePoint pointOf(const Material& material, glm::vec3 position, glm::vec3 normal) {
    SurfacePoint p;
    p.material = &material;
    p.surface = constantSurfaceMaterial(material);
    p.toEye = {0, 0, 1};
    p.position = position;
    p.normal = normal;
    return p;
}

// A 32 x 16 view of two surfaces: the left half a floor (normal +y), the right half a wall (normal +x).
struct Fixture {
    static constexpr int kW = 32, kH = 16;
    Material material;
    std::vector<SurfacePoint> points;
    Fixture() {
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW; ++x)
                points.push_back(
                    x < kW / 2 ? pointOf(material, {0.01f * x, 0.0f, 0.01f * y}, {0, 1, 0})
                               : pointOf(material, {0.16f, 0.01f * (x - kW / 2), 0.01f * y}, {1, 0, 0}));
    }
};

TEST(Denoise, KeepsConstantsReducesNoiseAndDoesNotMixSurfaces) {
    Fixture f;
    std::vector<float> values(f.points.size());
    for (size_t i = 0; i < values.size(); ++i) {
        const bool wall = (i % Fixture::kW) >= Fixture::kW / 2;
        values[i] = (wall ? 1.0f : 0.0f) + 0.2f * (hashToUnit(i, 0) - 0.5f);  // two levels plus noise
    }
    const glm::vec3 eye(0.1f, 1.0f, 0.1f);
    const std::vector<float> out =
        denoise(values, 1, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, DenoiseSettings{});
    double noiseIn = 0.0, noiseOut = 0.0;
    for (size_t i = 0; i < values.size(); ++i) {
        const bool wall = (i % Fixture::kW) >= Fixture::kW / 2;
        const float level = wall ? 1.0f : 0.0f;
        noiseIn += std::pow(values[i] - level, 2.0);
        noiseOut += std::pow(out[i] - level, 2.0);
        // The pixels next to the crease keep their own surface's level: nothing leaks across.
        EXPECT_NEAR(out[i], level, 0.1f) << i;
    }
    EXPECT_LT(noiseOut, 0.25 * noiseIn);
    // A constant stays exactly constant (up to rounding).
    std::vector<float> constant(f.points.size(), 0.7f);
    for (float v : denoise(constant, 1, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, DenoiseSettings{}))
        EXPECT_NEAR(v, 0.7f, 1e-6f);
    // Radius 0 is the identity.
    EXPECT_EQ(denoise(values, 1, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, DenoiseSettings{0}), values);
}

// Sparse samples (stride 3) whose windows hold only zeros filter to exactly zero without being weighed; the
// holes (pixels without a usable sample) do not depend on the values; a window with one non-zero sample
// interpolates it, multi-channel values too.
TEST(Denoise, SparseZerosStayZeroAndHolesDoNotDependOnValues) {
    Fixture f;
    // Some points invalid: a stripe of columns the samples (x = 0, 3, ...) miss, so their pixels may be
    // holes.
    for (int y = 0; y < Fixture::kH; ++y)
        for (int x = 0; x < Fixture::kW; ++x)
            if (x % 3 == 0 && x > 20) f.points[static_cast<size_t>(y) * Fixture::kW + x].material = nullptr;
    const glm::vec3 eye(0.1f, 1.0f, 0.1f);
    DenoiseSettings sparse;
    sparse.stride = 3;
    const int channels = 5;  // not one of the specialised counts
    std::vector<float> zeros(f.points.size() * channels, 0.0f), ones(zeros.size(), 1.0f), spike(zeros);
    const size_t spikePixel = 3 * Fixture::kW + 3;  // a sample of the floor
    for (int c = 0; c < channels; ++c) spike[spikePixel * channels + c] = 1.0f + static_cast<float>(c);
    std::vector<size_t> holesZeros, holesOnes, holesSpike;
    const auto outZeros =
        denoise(zeros, channels, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, sparse, &holesZeros);
    const auto outOnes =
        denoise(ones, channels, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, sparse, &holesOnes);
    const auto outSpike =
        denoise(spike, channels, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, sparse, &holesSpike);
    EXPECT_FALSE(holesOnes.empty());
    EXPECT_EQ(holesZeros, holesOnes);
    EXPECT_EQ(holesSpike, holesOnes);
    for (float v : outZeros) EXPECT_EQ(v, 0.0f);
    for (size_t i = 0; i < f.points.size(); ++i) {
        if (!f.points[i].valid() || std::count(holesOnes.begin(), holesOnes.end(), i)) continue;
        for (int c = 0; c < channels; ++c) EXPECT_NEAR(outOnes[i * channels + c], 1.0f, 1e-6f) << i;
    }
    // Next to the spike: a positive share of it in every channel, in proportion; far away (the wall): zero.
    const size_t near = spikePixel + 1, far = 10 * Fixture::kW + 28;
    EXPECT_GT(outSpike[near * channels], 0.0f);
    for (int c = 0; c < channels; ++c)
        EXPECT_NEAR(outSpike[near * channels + c], outSpike[near * channels] * (1.0f + c), 1e-5f);
    EXPECT_EQ(outSpike[far * channels], 0.0f);
    // Interpolating between the filtered samples: the same zeros and holes.
    sparse.interpolate = true;
    std::vector<size_t> holesInterpolated;
    for (float v :
         denoise(zeros, channels, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, sparse, &holesInterpolated))
        EXPECT_EQ(v, 0.0f);
    EXPECT_EQ(holesInterpolated, holesOnes);
}

// settings.interpolate: the pixels between samples blend the filtered samples around them on their own
// surface: a linear ramp stays linear away from the image border, and nothing crosses the crease.
TEST(Denoise, InterpolationBetweenSamplesKeepsRampsAndEdges) {
    Fixture f;
    const glm::vec3 eye(0.1f, 1.0f, 0.1f);
    std::vector<float> values(f.points.size(), 0.0f);
    for (int y = 0; y < Fixture::kH; y += 2)
        for (int x = 0; x < Fixture::kW; x += 2) {
            const bool wall = x >= Fixture::kW / 2;
            values[static_cast<size_t>(y) * Fixture::kW + x] = wall ? 5.0f : 0.1f * static_cast<float>(y);
        }
    DenoiseSettings settings;
    settings.stride = 2;
    settings.interpolate = true;
    std::vector<size_t> holes;
    const auto out = denoise(values, 1, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, settings, &holes);
    EXPECT_TRUE(holes.empty());
    for (int y = 0; y < Fixture::kH; ++y)
        for (int x = 0; x < Fixture::kW; ++x) {
            const float v = out[static_cast<size_t>(y) * Fixture::kW + x];
            if (x >= Fixture::kW / 2)
                EXPECT_NEAR(v, 5.0f, 1e-5f) << x << "," << y;  // the wall: its own constant only
            else if (y >= 4 && y <= Fixture::kH - 6)  // the floor away from the top and bottom rows, within
                // the floor under the bilinear weights (1e-3 of the next sample row's 0.2 more)
                EXPECT_NEAR(v, 0.1f * static_cast<float>(y), 1e-3f) << x << "," << y;
        }
    // Without interpolation every pixel is filtered on its own, over the window of its nearest sample row
    // (the next one between two): the ramp on the sample rows, a step of a row between them.
    settings.interpolate = false;
    const auto direct = denoise(values, 1, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, settings);
    for (int y = 4; y <= Fixture::kH - 6; ++y)
        EXPECT_NEAR(direct[static_cast<size_t>(y) * Fixture::kW + 3], 0.1f * static_cast<float>(y + y % 2),
                    1e-4f)
            << y;
}

// A plan of the interpolation weights over fixed surfaces gives the filter's bits without it, also for a pass
// in which some of those surfaces are invalid (hidden by an object) inside `planChanged`; the plan is kept
// for later passes, which use it as they are.
TEST(Denoise, InterpolationPlanGivesTheSameBits) {
    Fixture f;
    const glm::vec3 eye(0.1f, 1.0f, 0.1f);
    std::vector<float> values(f.points.size() * 3, 0.0f);
    for (int y = 0; y < Fixture::kH; y += 4)
        for (int x = 0; x < Fixture::kW; x += 4)
            for (int c = 0; c < 3; ++c)
                values[(static_cast<size_t>(y) * Fixture::kW + x) * 3 + c] =
                    x == 8 && y == 8 ? 0.0f : std::sin(0.7f * x + 1.3f * y + c);
    InterpolationPlan plan;
    plan.surfaces = f.points;
    for (int pass = 0; pass < 3; ++pass) {
        // Pass 1 hides a block of pixels (and so the samples in it) as an object would.
        std::vector<SurfacePoint> points = f.points;
        PixelRect hidden{};
        if (pass == 1) {
            hidden = {9, 3, 15, 10};
            for (int y = hidden.y0; y < hidden.y1; ++y)
                for (int x = hidden.x0; x < hidden.x1; ++x)
                    points[static_cast<size_t>(y) * Fixture::kW + x] = {};
        }
        DenoiseSettings settings;
        settings.stride = 4;
        settings.interpolate = true;
        std::vector<size_t> holesWithout, holesWith;
        const auto without =
            denoise(values, 3, points, Fixture::kW, Fixture::kH, eye, 0.01f, settings, &holesWithout);
        settings.plan = &plan;
        settings.planChanged = hidden;
        const auto with =
            denoise(values, 3, points, Fixture::kW, Fixture::kH, eye, 0.01f, settings, &holesWith);
        EXPECT_EQ(plan.stride, 4);
        EXPECT_EQ(holesWith, holesWithout);
        for (size_t i = 0; i < with.size(); ++i)
            ASSERT_EQ(std::memcmp(&with[i], &without[i], sizeof(float)), 0)
                << "pass " << pass << " value " << i;
    }
}

// The filter eight pixels at a time in vector lanes (DenoiseSettings::lanes: the samples filtered, the pixels
// between them interpolated, with and without a kept plan, or every pixel filtered) gives the bits and holes
// of one pixel at a time: over a view of a floor, a wall, a bumpy ball in front of them and two poles thinner
// than a cell (depth edges, normals of every direction, pixels without a surface, pixels without a sample on
// their surface: the full filter, and holes), at strides 1 to 16, odd ones too, with 1, 3 and 6 channels,
// radius 1 and 2, another normal power, over the whole image and a rectangle, with and without a mask of
// pixels to filter, a block of the plan's surfaces hidden; the values smooth with zeros around a disk that
// holds one of the poles, and a lone spike: a third of the windows and more hold values, so that the filter
// runs in lanes.
TEST(Denoise, TheFilterInLanesGivesTheSameBits) {
    if (!denoiseLanesAvailable())
        GTEST_SKIP() << "this CPU has no AVX2: the filter interpolates one pixel at a time";
    constexpr int kW = 93, kH = 61;
    Material material;
    std::vector<SurfacePoint> points(static_cast<size_t>(kW) * kH);
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            SurfacePoint& p = points[static_cast<size_t>(y) * kW + x];
            const float u = 0.01f * static_cast<float>(x), v = 0.01f * static_cast<float>(y);
            const glm::vec2 d(static_cast<float>(x - 50), static_cast<float>(y - 30));
            if ((x * 7 + y * 13) % 97 == 0) continue;  // no surface
            if (glm::length(d) < 18.0f) {              // the ball, bumpy
                const float r = glm::length(d) / 18.0f;
                const glm::vec3 n =
                    glm::normalize(glm::vec3(d.x / 18.0f, d.y / 18.0f,
                                             std::sqrt(std::max(1.0f - r * r, 0.0f)) +
                                                 0.1f * std::sin(0.9f * x) * std::cos(0.7f * y)));
                p = pointOf(material, {u, v, 1.0f + 0.18f * n.z}, n);
            } else if ((x >= 20 && x < 25) || (x >= 85 && x < 89)) {
                p = pointOf(material, {u, v, 0.6f},
                            {0, 0, 1});  // a pole before the wall, thinner than a cell
            } else if (y < 35) {
                p = pointOf(material, {u, v, 0.0f}, {0, 0, 1});  // the wall
            } else {
                p = pointOf(material, {u, 0.35f, 0.01f * (y - 35)}, {0, 1, 0});  // the floor
            }
        }
    const glm::vec3 eye(0.45f, 0.3f, 2.0f);
    std::vector<uint8_t> mask(points.size());
    for (size_t i = 0; i < mask.size(); ++i) mask[i] = (i * 2654435761u >> 7) % 5 != 0;
    size_t holes = 0;
    for (const int channels : {1, 3, 6})
        for (const int stride : {1, 2, 3, 4, 8, 16})
            for (int variant = 0; variant < 8; ++variant) {
                const bool interpolate = variant < 4;
                if (stride == 1 && interpolate) continue;
                std::vector<float> values(points.size() * channels, 0.0f);
                for (size_t i = 0; i < points.size(); ++i) {
                    const int x = static_cast<int>(i % kW), y = static_cast<int>(i / kW);
                    const bool zero = std::hypot(x - 40.0f, y - 28.0f) > 26.0f + 10.0f * (variant & 1);
                    for (int c = 0; c < channels; ++c)
                        values[i * channels + c] =
                            zero ? 0.0f : 0.2f + 0.1f * std::sin(0.3f * x + 0.5f * y + c) - 0.05f * c;
                }
                values[(static_cast<size_t>(48) * kW + 80) * channels] = 2.0f;  // a spike among zeros
                DenoiseSettings settings;
                settings.stride = stride;
                settings.interpolate = interpolate;
                settings.radius = variant % 4 < 2 ? 1 : 2;
                if (variant % 4 == 3) settings.normalPower = 5;
                if (variant % 4 == 2) settings.filtered = mask;
                const bool inRect = variant % 4 == 1;
                const PixelRect rect = inRect ? PixelRect{7, 5, 88, 58} : PixelRect{0, 0, kW, kH};
                // With a plan (whole images only): its surfaces the view, the pass's a block of them hidden.
                for (const bool withPlan : {false, true}) {
                    if (withPlan && (!interpolate || inRect)) continue;
                    std::vector<float> inLanes = values, alone = values;
                    std::vector<size_t> holesInLanes, holesAlone;
                    std::vector<SurfacePoint> view = points;
                    const PixelRect hidden = withPlan ? PixelRect{41, 22, 63, 37} : rect;
                    for (int y = 0; y < kH; ++y)
                        for (int x = 0; x < kW; ++x)
                            if ((x >= hidden.x0 && x < hidden.x1 && y >= hidden.y0 && y < hidden.y1) ==
                                withPlan)
                                view[static_cast<size_t>(y) * kW + x].material = nullptr;
                    InterpolationPlan planInLanes, planAlone;
                    planInLanes.surfaces = planAlone.surfaces = points;
                    settings.planChanged = withPlan ? hidden : PixelRect{};
                    settings.lanes = true;
                    settings.plan = withPlan ? &planInLanes : nullptr;
                    denoiseInto(inLanes, channels, view, kW, kH, eye, 0.005f, settings, &holesInLanes, &rect);
                    settings.lanes = false;
                    settings.plan = withPlan ? &planAlone : nullptr;
                    denoiseInto(alone, channels, view, kW, kH, eye, 0.005f, settings, &holesAlone, &rect);
                    EXPECT_EQ(holesInLanes, holesAlone);
                    for (size_t i = 0; i < alone.size(); ++i)
                        ASSERT_EQ(std::memcmp(&inLanes[i], &alone[i], sizeof(float)), 0)
                            << "channels " << channels << " stride " << stride << " variant " << variant
                            << " plan " << withPlan << " value " << i << ": " << inLanes[i] << " against "
                            << alone[i];
                    EXPECT_NE(inLanes, values);
                    holes += holesAlone.size();
                }
            }
    EXPECT_GT(holes, 0u);  // the pole's pixels at the largest strides
}

// A pass over a rectangle that holds every valid point (the objects' pixels) keeps only the rectangle's
// samples and one more on each side: the same bits and holes as over the whole image, for rectangles whose
// edges fall on samples and between them, at stride 1 and 3, filtered and interpolated.
TEST(Denoise, ARectanglesPassGivesTheSameBitsAsTheWholeImages) {
    Fixture f;
    const glm::vec3 eye(0.1f, 1.0f, 0.1f);
    std::vector<float> values(f.points.size() * 3);
    for (size_t i = 0; i < values.size(); ++i) values[i] = std::sin(0.37f * static_cast<float>(i));
    for (const PixelRect rect : {PixelRect{5, 2, 27, 13}, PixelRect{6, 3, 25, 12}, PixelRect{0, 4, 20, 16}}) {
        std::vector<SurfacePoint> points = f.points;
        for (int y = 0; y < Fixture::kH; ++y)
            for (int x = 0; x < Fixture::kW; ++x)
                if (x < rect.x0 || x >= rect.x1 || y < rect.y0 || y >= rect.y1)
                    points[static_cast<size_t>(y) * Fixture::kW + x] = {};
        for (const int stride : {1, 3})
            for (const bool interpolate : {false, true}) {
                DenoiseSettings settings;
                settings.stride = stride;
                settings.interpolate = interpolate;
                std::vector<float> whole = values, inRect = values;
                std::vector<size_t> holesWhole, holesRect;
                denoiseInto(whole, 3, points, Fixture::kW, Fixture::kH, eye, 0.01f, settings, &holesWhole);
                denoiseInto(inRect, 3, points, Fixture::kW, Fixture::kH, eye, 0.01f, settings, &holesRect,
                            &rect);
                EXPECT_EQ(holesRect, holesWhole);
                for (size_t i = 0; i < whole.size(); ++i)
                    ASSERT_EQ(std::memcmp(&whole[i], &inRect[i], sizeof(float)), 0)
                        << "rect " << rect.x0 << "," << rect.y0 << " stride " << stride << " interpolate "
                        << interpolate << " value " << i;
            }
    }
}

// With a plan, a cell all of whose filtered samples are zero is filled with zeros without its weights; a
// cell with one non-zero sample (whichever of its four) is interpolated: a single value among zeros, radius
// 1, gives the same bits and holes as without the plan.
TEST(Denoise, InterpolationPlanFillsCellsOfZerosAsWithoutIt) {
    Fixture f;
    const glm::vec3 eye(0.1f, 1.0f, 0.1f);
    for (int spike = 0; spike < 16; ++spike) {  // the value's sample: column spike / 2, row 1 + spike % 2
        const size_t pixel = 4 * static_cast<size_t>(1 + spike % 2) * Fixture::kW + 4 * (spike / 2);
        std::vector<float> values(f.points.size() * 3, 0.0f);
        for (int c = 0; c < 3; ++c) values[pixel * 3 + c] = 1.0f + c;
        DenoiseSettings settings;
        settings.radius = 1;
        settings.stride = 4;
        settings.interpolate = true;
        std::vector<size_t> holesWithout, holesWith;
        const auto without =
            denoise(values, 3, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, settings, &holesWithout);
        InterpolationPlan plan;
        plan.surfaces = f.points;
        settings.plan = &plan;
        const auto with =
            denoise(values, 3, f.points, Fixture::kW, Fixture::kH, eye, 0.01f, settings, &holesWith);
        EXPECT_EQ(holesWith, holesWithout);
        EXPECT_GT(std::count(plan.weighted.begin(), plan.weighted.end(), 1), 0);
        for (size_t i = 0; i < with.size(); ++i)
            ASSERT_EQ(std::memcmp(&with[i], &without[i], sizeof(float)), 0)
                << "spike " << spike << " value " << i;
    }
}

// fillHoles at stride 16 (a finer grid every 4 pixels) on a strip of wall 12 pixels wide between two parts of
// a floor, all of the strip's pixels holes: only the finer grid's are traced; the others blend them (a linear
// ramp stays linear where a cell's four corners are traced); a hole whose cell has no traced corner on its
// surface is traced itself. At stride 4 every hole is traced.
TEST(Denoise, HolesAreTracedOnAFinerGridAndBlendedBetween) {
    constexpr int kW = 64, kH = 32, kStripX0 = 40, kStripX1 = 52;
    Material material;
    std::vector<SurfacePoint> points;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x)
            points.push_back(x >= kStripX0 && x < kStripX1
                                 ? pointOf(material, {0.3f, 0.01f * (x - kStripX0), 0.01f * y}, {1, 0, 0})
                                 : pointOf(material, {0.01f * x, 0.0f, 0.01f * y}, {0, 1, 0}));
    Camera camera;
    camera.width = kW, camera.height = kH;
    camera.fx = camera.fy = 100.0f;
    camera.worldFromCamera = glm::translate(glm::mat4(1.0f), glm::vec3(0.1f, 1.0f, 0.1f));
    auto ramp = [&](size_t i) {
        return 0.5f + 0.01f * static_cast<float>(i % kW) + 0.02f * static_cast<float>(i / kW);
    };
    std::vector<size_t> holes;
    for (size_t i = 0; i < points.size(); ++i)
        if (static_cast<int>(i % kW) >= kStripX0 && static_cast<int>(i % kW) < kStripX1) holes.push_back(i);
    const size_t lonely = 5 * kW + 10;  // on the floor, in a cell whose corners are not holes
    holes.insert(std::upper_bound(holes.begin(), holes.end(), lonely), lonely);
    for (const int stride : {16, 4}) {
        SCOPED_TRACE(stride);
        DenoiseSettings settings;
        settings.stride = stride;
        std::vector<uint32_t> traced;
        std::vector<glm::vec3> values(points.size(), glm::vec3(-1.0f));
        fillHoles(values, 1, points, camera, settings, holes, [&](std::span<const uint32_t> pixels) {
            std::vector<glm::vec3> out(points.size(), glm::vec3(0.0f));
            for (uint32_t i : pixels) {
                traced.push_back(i);
                out[i] = glm::vec3(ramp(i), 2.0f * ramp(i), 1.0f);
            }
            return out;
        });
        std::sort(traced.begin(), traced.end());
        if (stride == 4) {
            EXPECT_EQ(traced, std::vector<uint32_t>(holes.begin(), holes.end()));
            continue;
        }
        // The finer grid's holes (x = 40, 44, 48; every 4th row) and the lonely one.
        EXPECT_EQ(traced.size(), 3u * (kH / 4) + 1);
        EXPECT_TRUE(std::binary_search(traced.begin(), traced.end(), static_cast<uint32_t>(lonely)));
        for (size_t i : holes) {
            const int x = static_cast<int>(i % kW), y = static_cast<int>(i / kW);
            ASSERT_NE(values[i].x, -1.0f) << x << "," << y;  // every hole has its value
            EXPECT_EQ(values[i].z, 1.0f);                    // blends of ones
            if (x >= kStripX0 && x < kStripX0 + 8 && y < 28) {
                EXPECT_NEAR(values[i].x, ramp(i), 1e-5f) << x << "," << y;
                EXPECT_NEAR(values[i].y, 2.0f * ramp(i), 1e-5f) << x << "," << y;
            }
        }
        // Pixels that are not holes are left alone.
        EXPECT_EQ(values[0], glm::vec3(-1.0f));
    }
}

}  // namespace
}  // namespace deltagi
