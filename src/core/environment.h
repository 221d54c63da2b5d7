// Environment maps (include/deltagi/environment.h): the equirectangular mapping, the projections of a light
// camera's image (fish-eye, mirror ball) converted to it, the repair of bad pixels, and lookups.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "deltagi/environment.h"
#include "deltagi/image.h"

namespace deltagi {

// ---- the equirectangular mapping (environment frame, see deltagi/environment.h) ---------------------------

// Unit direction of the map point (u, v) in [0, 1]^2 (u along the width, v down the height).
glm::vec3 equirectDirection(float u, float v);
// The map point (u, v) of a direction (need not be unit); u in [0, 1), v in [0, 1].
glm::vec2 equirectUv(glm::vec3 direction);
// Elevation (radians) of the top edge of row `row` of a map `height` rows high: pi (0.5 - row / height).
double equirectRowElevation(int row, int height);
// Exact solid angle (sr) of one pixel of row `row` of a width x height map: the band's area over the width.
// The rows of a map add up to 4 pi.
double equirectPixelSolidAngle(int row, int width, int height);
// The integral of the radiance over the sphere, sum L dOmega (W/m^2 per channel): what the map sends to a
// point, and what its extracted lights must carry in total.
glm::dvec3 integrateSphere(const Image& equirect);
// Bilinear lookup: u wraps around, v is clamped.
glm::vec3 sampleEquirect(const Image& equirect, glm::vec2 uv);

// Rec. 709 luminance of linear RGB.
inline float luminance(glm::vec3 rgb) {
    return 0.2126f * rgb.x + 0.7152f * rgb.y + 0.0722f * rgb.z;
}

// ---- light camera projections -----------------------------------------------------------------------------

// A fish-eye image. Its camera looks straight up (environment +y) with the image's top towards -z and its
// right towards -x (as an upward-looking camera sees the sky; the convention of the shared
// sky_fisheye_equidistant_512.hdr). A pixel at distance r from `center` sees the angle theta from the axis:
//   equidistant: r = radius * theta / (fov / 2);   equisolid: r = radius * sin(theta / 2) / sin(fov / 4).
struct FisheyeProjection {
    enum class Model { Equidistant, Equisolid };
    Model model = Model::Equidistant;
    glm::vec2 center{0.0f};  // pixels, same pixel convention as the camera (pixel (i, j) centred at i + 0.5)
    float radius = 0.0f;     // pixels: the image circle, where theta = fov / 2
    float fovDeg = 180.0f;   // full field of view, in (0, 360]
};

// A mirror ball photographed from far away (orthographically) by a camera looking along -z with +y up: the
// ball's centre reflects +z (the camera), its rim -z (what is behind the ball).
struct MirrorBallProjection {
    glm::vec2 center{0.0f};  // pixels
    float radius = 0.0f;     // pixels: the ball's silhouette
};

// Where a direction (environment frame) lands in the image; nothing outside the field of view / the ball.
std::optional<glm::vec2> fisheyePixel(glm::vec3 direction, const FisheyeProjection& projection);
std::optional<glm::vec2> mirrorBallPixel(glm::vec3 direction, const MirrorBallProjection& projection);

// Equirectangular maps (2 height x height) of a fish-eye or mirror-ball image, by bilinear lookups;
// directions the image does not see are 0. A `height` of 0 picks one that keeps the image's resolution at its
// centre.
Image equirectFromFisheye(const Image& fisheye, const FisheyeProjection& projection, int height = 0);
Image equirectFromMirrorBall(const Image& ball, const MirrorBallProjection& projection, int height = 0);

// The same conversion made once for images of one size and projection and applied to each (a light camera's
// frames): where every sub-sample of every map pixel looks the image up, found once. apply() gives what
// equirectFromFisheye() / equirectFromMirrorBall() give, bit for bit.
class EquirectConversion {
  public:
    static EquirectConversion fromFisheye(int sourceWidth, int sourceHeight,
                                          const FisheyeProjection& projection, int height = 0);
    static EquirectConversion fromMirrorBall(int sourceWidth, int sourceHeight,
                                             const MirrorBallProjection& projection, int height = 0);
    // `source` must be sourceWidth() x sourceHeight().
    Image apply(const Image& source) const;
    int sourceWidth() const { return sourceWidth_; }
    int sourceHeight() const { return sourceHeight_; }

  private:
    // A bilinear lookup: the top-left of its four pixels (before clamping to the image) and its weights; a
    // sub-sample the image does not see has none (x0 = kUnseen).
    struct Lookup {
        int x0, y0;
        float fx, fy;
    };
    static constexpr int kUnseen = std::numeric_limits<int>::min();
    template <typename PixelOf>
    static EquirectConversion make(int sourceWidth, int sourceHeight, int height, PixelOf&& pixelOf);
    int sourceWidth_ = 0, sourceHeight_ = 0, height_ = 0;
    std::vector<Lookup> lookups_;  // per map pixel in row order, its sub-samples in order
};

// ---- repair
// -------------------------------------------------------------------------------------------------

// Sets NaN, infinite and negative values to 0 (a light probe's radiance is finite and never negative);
// returns how many pixels had such a value.
size_t sanitizeRadiance(Image& image);

// ---- lookups in the world ---------------------------------------------------------------------------------

// The map's radiance arriving from world direction `direction` (bilinear).
glm::vec3 environmentRadiance(const Environment& environment, glm::vec3 direction);

}  // namespace deltagi
