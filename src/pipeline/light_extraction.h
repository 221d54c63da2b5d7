// Light extraction from an environment map: the map is cut into regions of sky and each becomes one
// directional light at its energy centroid, carrying the region's whole light, so that the lights together
// carry exactly the map's light. They drive the reflective shadow maps and the shadow cones (§3.5) like any
// other light; the sky term (sky_light.h) adds what they miss.
//
//   median cut (Debevec 2005, "A median cut algorithm for light probe sampling"): every region is split
//   across
//     its longest side (widths measured on the sphere: times the cosine of the latitude) where the energy on
//     both sides is equal;
//   variance minimization (Viriyothai & Debevec 2009): every region is split at the cut, across either side,
//     that minimizes the summed energy-weighted variance of the directions in the two halves.
// Each round splits every region (as the papers do, giving 2^n lights); when `count` is not a power of two
// the last round splits the regions with the most energy first.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "deltagi/image.h"
#include "deltagi/options.h"

namespace deltagi {

struct ExtractedLight {
    glm::vec3 direction{0, 1, 0};  // unit, environment frame, from the scene towards the light
    glm::vec3 irradiance{0.0f};    // sum of L dOmega over the region: W/m^2 on a surface facing the light
    float solidAngle = 0.0f;       // of the region, sr
};

// At most `count` lights (fewer when the map has fewer non-black regions than that); none for count <= 0.
std::vector<ExtractedLight> extractLights(const Image& equirect, int count, ExtractionMethod method);

}  // namespace deltagi
