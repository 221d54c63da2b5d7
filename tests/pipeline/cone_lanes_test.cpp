// The cones traced in SIMD lanes (cone_lanes.cpp) against the one-cone tracers, their definition.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "pipeline/cone_trace.h"
#include "pipeline/mipmap.h"

namespace deltagi {
namespace {

constexpr int kN = 32;
const VolumeRegion kRegion{glm::vec3(-1.0f), 2.0f, kN};

// A room of the real scene: a floor, a back wall and a ceiling lit unevenly, a few scattered occluders with
// incoherent normals; a ball of the objects in its middle (stored over a window around it, as the pipeline's
// object volumes are, or whole), a glowing one.
struct Room {
    MipVolume sceneVisibility, objectVisibility, objectWhole, fullLight, deltaLight, objectLight;

    explicit Room() {
        Grid3 scene(kN), object(kN), full(kN), delta(kN), objects(kN);
        std::mt19937 random(7);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        for (int z = 0; z < kN; ++z)
            for (int y = 0; y < kN; ++y)
                for (int x = 0; x < kN; ++x) {
                    glm::vec4 visibility(0.0f), light(0.0f);
                    const glm::vec3 colour(0.2f + 0.8f * unit(random), 0.5f, 0.1f + unit(random));
                    if (y == 2) visibility = {1.0f, 0.0f, -1.0f, 0.0f}, light = {colour * 0.6f, 1.0f};
                    if (x == 28) visibility = {1.0f, 1.0f, 0.0f, 0.0f}, light = {colour * 0.3f, 1.0f};
                    if (y == 29) visibility = {0.7f, 0.0f, 0.7f, 0.0f}, light = {colour * 1.5f * 0.7f, 0.7f};
                    if (unit(random) < 0.01f)
                        visibility = {0.5f, 0.1f, 0.1f, -0.1f}, light = {colour * 0.5f, 0.5f};
                    scene.at(x, y, z) = visibility;
                    full.at(x, y, z) = light;
                    const glm::vec3 d = glm::vec3(x, y, z) + 0.5f - glm::vec3(14.0f, 9.0f, 16.0f);
                    if (std::abs(glm::length(d) - 4.0f) < 0.8f) {
                        const glm::vec3 n = glm::normalize(d);
                        object.at(x, y, z) = {1.0f, -n.x, -n.y, -n.z};
                        objects.at(x, y, z) = {glm::vec3(0.8f, 0.4f, 0.2f) * (n.y > 0.0f ? 2.0f : 0.2f),
                                               1.0f};
                        full.at(x, y, z) = objects.at(x, y, z) + full.at(x, y, z);
                        delta.at(x, y, z) = objects.at(x, y, z);
                    } else if (light.w > 0.0f) {
                        // The objects' shadow on the floor below them.
                        delta.at(x, y, z) =
                            glm::vec4(-0.3f * glm::vec3(light) *
                                          (y == 2 && glm::length(glm::vec2(d.x, d.z)) < 5.0f ? 1.0f : 0.0f),
                                      0.0f);
                    }
                }
        const VoxelBox window{glm::ivec3(8, 3, 10), glm::ivec3(21, 16, 23)};
        sceneVisibility = buildMipChain(kRegion, scene);
        objectVisibility = buildMipChain(kRegion, PackedGrid3(object, window));
        objectWhole = buildMipChain(kRegion, object);
        fullLight = buildMipChain(kRegion, full);
        deltaLight = buildMipChain(kRegion, delta);
        objectLight = buildMipChain(kRegion, PackedGrid3(objects, window));
    }
};

// Cones of every kind: from inside and outside the volume, rays and wide cones, cut short or not.
std::vector<Cone> someCones(int count) {
    std::mt19937 random(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const float apertures[] = {0.0f, 0.05f, 0.3f, 0.52f, 1.2f};
    std::vector<Cone> cones;
    for (int i = 0; i < count; ++i) {
        Cone c;
        c.origin = glm::vec3(unit(random), unit(random), unit(random)) * (i % 7 == 0 ? 3.0f : 1.9f) -
                   (i % 7 == 0 ? 1.5f : 0.95f);
        glm::vec3 d(unit(random) - 0.5f, unit(random) - 0.5f, unit(random) - 0.5f);
        if (i % 11 == 0) d = glm::vec3(0.0f, 1.0f, 0.0f);  // along an axis
        c.direction = glm::normalize(d);
        c.tanHalfAngle = apertures[i % 5];
        c.jitter = unit(random);
        if (i % 3 == 0) c.maxDistance = 0.1f + unit(random);
        cones.push_back(c);
    }
    return cones;
}

// The two results of each cone agree to within rounding: a step's opacity can cross maxOcclusion in one and
// not in the other, which ends that cone a step apart, so a few cones may differ more than rounding alone.
void expectClose(const std::vector<glm::vec3>& lanes, const std::vector<glm::vec3>& alone) {
    float scale = 0.0f;
    for (const glm::vec3& v : alone)
        scale = std::max(scale, std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z))));
    ASSERT_GT(scale, 0.0f);
    int apart = 0;
    double sumLanes = 0.0, sumAlone = 0.0;
    for (size_t i = 0; i < alone.size(); ++i) {
        const float difference = glm::length(lanes[i] - alone[i]);
        EXPECT_LT(difference, 0.05f * scale) << "cone " << i;
        if (difference > 1e-3f * scale) ++apart;
        sumLanes += lanes[i].x + lanes[i].y + lanes[i].z;
        sumAlone += alone[i].x + alone[i].y + alone[i].z;
    }
    EXPECT_LE(apart, static_cast<int>(alone.size() / 100)) << "cones apart by more than rounding";
    EXPECT_NEAR(sumLanes, sumAlone, 1e-3 * std::abs(sumAlone));
}

ConeTraceSettings settingsWith(bool paper, float stepScale) {
    ConeTraceSettings s;
    s.paperAccumulation = paper;
    s.stepScale = stepScale;
    return s;
}

TEST(ConeLanes, LightConesGiveEachConesLightAsTracedAlone) {
    const Room room;
    const std::vector<Cone> cones = someCones(1000);
    for (const MipVolume* object :
         {&room.objectVisibility, &room.objectWhole, static_cast<const MipVolume*>(nullptr)})
        for (auto [paper, stepScale] :
             {std::pair{false, 0.5f}, std::pair{true, 0.5f}, std::pair{false, 0.35f}}) {
            SCOPED_TRACE(::testing::Message()
                         << "object "
                         << (object ? (object == &room.objectWhole ? "whole" : "windowed") : "none")
                         << ", paper " << paper << ", step " << stepScale);
            const ConeTraceSettings s = settingsWith(paper, stepScale);
            const VisibilityVolumes visibility{&room.sceneVisibility, object, VisibilityVolumes::Self::Scene};
            std::vector<glm::vec3> lanes(cones.size()), alone;
            int64_t laneSteps = 0, aloneSteps = 0;
            traceLightCones(cones, room.fullLight, visibility, s, lanes, &laneSteps);
            for (const Cone& c : cones)
                alone.push_back(traceLightCone(c, room.fullLight, visibility, s, &aloneSteps));
            expectClose(lanes, alone);
            EXPECT_NEAR(static_cast<double>(laneSteps), static_cast<double>(aloneSteps), 0.002 * aloneSteps);
        }
}

TEST(ConeLanes, LightChangeConesGiveEachConesChangeAsTracedAlone) {
    const Room room;
    const std::vector<Cone> cones = someCones(1000);
    for (bool byRays : {false, true})
        for (const MipVolume* objectLight : {&room.objectLight, static_cast<const MipVolume*>(nullptr)})
            for (auto self : {VisibilityVolumes::Self::Scene, VisibilityVolumes::Self::Object}) {
                SCOPED_TRACE(::testing::Message()
                             << "by rays " << byRays << ", object light " << (objectLight != nullptr)
                             << ", self " << static_cast<int>(self));
                ConeTraceSettings s = settingsWith(false, 0.5f);
                s.objectLightByRays = byRays;
                const VisibilityVolumes visibility{&room.sceneVisibility, &room.objectVisibility, self};
                std::vector<glm::vec3> lanes(cones.size()), alone;
                traceLightChangeCones(cones, room.fullLight, room.deltaLight, visibility, s, objectLight,
                                      lanes);
                for (const Cone& c : cones)
                    alone.push_back(
                        traceLightChangeCone(c, room.fullLight, room.deltaLight, visibility, s, objectLight));
                expectClose(lanes, alone);
            }
}

// Lanes share nothing: a cone's light is the same whichever cones are traced beside it, bit for bit.
TEST(ConeLanes, AConesLightDoesNotDependOnTheConesBesideIt) {
    const Room room;
    const std::vector<Cone> cones = someCones(203);
    const VisibilityVolumes visibility{&room.sceneVisibility, &room.objectVisibility,
                                       VisibilityVolumes::Self::Scene};
    const ConeTraceSettings s;
    std::vector<glm::vec3> all(cones.size());
    traceLightChangeCones(cones, room.fullLight, room.deltaLight, visibility, s, &room.objectLight, all);
    for (size_t i = 0; i < cones.size(); i += 17) {
        glm::vec3 one;
        traceLightChangeCones(std::span(&cones[i], 1), room.fullLight, room.deltaLight, visibility, s,
                              &room.objectLight, std::span(&one, 1));
        EXPECT_EQ(one, all[i]) << "cone " << i;
    }
    // In the reverse order, each lane meets other neighbours.
    const std::vector<Cone> reversed(cones.rbegin(), cones.rend());
    std::vector<glm::vec3> back(cones.size());
    traceLightChangeCones(reversed, room.fullLight, room.deltaLight, visibility, s, &room.objectLight, back);
    for (size_t i = 0; i < cones.size(); ++i) EXPECT_EQ(back[cones.size() - 1 - i], all[i]) << "cone " << i;
}

}  // namespace
}  // namespace deltagi
