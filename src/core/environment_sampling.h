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
    // Both at once (one look-up of the pixel), for a unit direction.
    struct Value {
        glm::vec3 radiance{0.0f};
        float pdf = 0.0f;
    };
    Value value(glm::vec3 worldDirection) const;
    // Whether value() is zero for every direction within `halfAngle` (radians) of `worldAxis` (unit), all of
    // them below the map's lowest lit row (by a margin wider than the floats' error in making them).
    bool darkCone(glm::vec3 worldAxis, float halfAngle) const;

    // sample(u1, u2) in steps, for culling samples before drawing them: the row it falls in (from u1 alone),
    // the column in that row, and the sample drawn in the pixel so found, the same as sample(u1, u2).
    int rowOf(float u1) const;
    int columnOf(int row, float u2) const;
    glm::ivec2 pixelOf(float u1, float u2) const;
    Sample sample(float u1, float u2, glm::ivec2 pixel) const;
    // The world direction of a pixel's centre, which lies within pixelRadius() (radians) of every sample
    // drawn in the pixel.
    glm::vec3 pixelCentre(glm::ivec2 pixel) const;
    float pixelRadius() const { return pixelRadius_; }
    // The elevation (radians, in the environment's frame) of the centre of a row: its pixel centres are at
    // least |that - elevationOf(d)| from a direction d, so samples can be culled by row before their column
    // is looked up.
    float rowElevation(int row) const { return rowElevations_[row]; }
    // The elevation of a world direction in the environment's frame.
    float elevationOf(glm::vec3 worldDirection) const;

  private:
    glm::ivec2 pixelOf(glm::vec3 worldDirection) const;
    glm::ivec2 pixelAt(glm::vec3 localDirection) const;  // in the environment's frame
    glm::vec3 rgbAt(glm::ivec2 pixel) const {
        const float* rgb = &pixels_[3 * (static_cast<size_t>(pixel.y) * width_ + pixel.x)];
        return {rgb[0], rgb[1], rgb[2]};
    }
    float meanRadiance(glm::ivec2 pixel) const;

    const Environment& environment_;
    glm::mat3 environmentFromWorld_;
    const float* pixels_;  // environment_.radiance's, RGB
    int width_, height_;
    // Directions (unit, environment frame) whose y is below this lie below the lowest row with any light:
    // black (a fish-eye light camera's lower hemisphere), known without finding their pixel.
    float darkBelowY_ = 2.0f;
    double total_ = 0.0;              // sum over pixels of meanRadiance * dOmega
    std::vector<double> rowCdf_;      // height + 1 entries, 0 ... 1
    std::vector<double> columnCdfs_;  // per row, width + 1 entries, 0 ... 1
    // Where the search for u starts: the interval of floor(u * n) / n (rows: n = height; each row's columns:
    // n = width), so that a sample scans a step or two instead of searching the whole cdf.
    std::vector<int> rowGuide_, columnGuides_;
    std::vector<glm::vec3> rowCentres_;     // per row: (cos, sin, 0) of the elevation of its centre
    std::vector<float> rowElevations_;      // per row: the elevation of its centre
    std::vector<glm::vec2> columnCentres_;  // per column: (sin, -cos) of the longitude of its centre
    float pixelRadius_ = 0.0f;
};

}  // namespace deltagi
