// The real illumination recorded by a light camera (the "Light Camera" of the paper's Fig. 2): an environment
// map, i.e. the radiance arriving from every direction from far away.
//
// Whatever the input projection (equirectangular, fish-eye, mirror ball), the map is held as an
// equirectangular image in the environment's own frame; `worldFromEnvironment` turns it in the world.
//
// Environment frame (the convention of the shared light probes, shared/data/photos/*/camera.json): +y up; the
// image's centre column looks along -z, and turning right in the image turns towards +x. For pixel (col, row)
// of a W x H map, u = (col + 0.5)/W, v = (row + 0.5)/H, phi = 2 pi (u - 0.5), theta = pi (0.5 - v)
// (elevation):
//   direction = (sin(phi) cos(theta), sin(theta), -cos(phi) cos(theta)).
#pragma once

#include <filesystem>
#include <vector>

#include <glm/glm.hpp>

#include "deltagi/export.h"
#include "deltagi/image.h"

DELTAGI_API_BEGIN
namespace deltagi {

// The environment minus the extracted lights (so that nothing is counted twice), prefiltered for cones of
// growing aperture: level l is the residual convolved with a kernel of half-angle halfAngles[l] (about twice
// the previous one), stored at a resolution that halves with each level. Values may be negative (where a
// light carries more than the map around it).
struct SkyPyramid {
    std::vector<Image> levels;      // equirectangular, environment frame
    std::vector<float> halfAngles;  // radians, increasing
    bool empty() const { return levels.empty(); }
};

struct Environment {
    std::filesystem::path file;  // for messages
    Image radiance;              // equirectangular, linear RGB radiance, times the intensity, finite and >= 0
    glm::mat3 worldFromEnvironment{1.0f};  // a rotation
    SkyPyramid sky;  // empty unless options.environment.sky and options.shadow.method "cones"

    glm::mat3 environmentFromWorld() const { return glm::transpose(worldFromEnvironment); }
};

struct Scene;
// Lights `scene` with `environment` (its radiance and rotation set) according to scene.options.environment:
// extracts the directional lights (replacing any extracted before; the scene file's own lights stay),
// prefilters the sky for the cones (sky_light.h; only with options.shadow.method "cones"), and stores the
// environment in the scene. The scene loader calls it for "environment".
void setEnvironment(Scene& scene, Environment environment);

}  // namespace deltagi
DELTAGI_API_END
