// Importance sampling of an environment map for the reference path tracer: a direction is drawn with a
// probability proportional to the map's radiance (mean of RGB) times the solid angle of its pixel, i.e. a
// pdf per unit solid angle proportional to the radiance itself. The map is taken as piecewise constant over
// its pixels, which is what radiance() returns, so that sampling and evaluation agree exactly.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "deltagi/environment.h"

namespace deltagi {

class EnvironmentSampler {
  public:
    // Holds a reference: `environment` must outlive the sampler.
    explicit EnvironmentSampler(const Environment& environment);

    struct Sample {
        glm::vec3 wi{0.0f};        // unit, world space, towards the environment
        glm::vec3 radiance{0.0f};  // arriving from wi
        float pdf = 0.0f;          // per unit solid angle; 0: no sample (a black map)
    };
    // Two uniform numbers in [0, 1): the first picks the row and the elevation in it, the second the column
    // and the longitude in it (uniform in solid angle within the pixel).
    Sample sample(float u1, float u2) const;
    float pdf(glm::vec3 worldDirection) const;
    glm::vec3 radiance(glm::vec3 worldDirection) const;

  private:
    glm::ivec2 pixelOf(glm::vec3 worldDirection) const;
    float meanRadiance(glm::ivec2 pixel) const;

    const Environment& environment_;
    int width_, height_;
    double total_ = 0.0;              // sum over pixels of meanRadiance * dOmega
    std::vector<double> rowCdf_;      // height + 1 entries, 0 ... 1
    std::vector<double> columnCdfs_;  // per row, width + 1 entries, 0 ... 1
};

}  // namespace deltagi
