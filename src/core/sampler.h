// The path tracer's sample values: Owen-scrambled Sobol' points (Burley 2020, "Practical Hash-based Owen
// Scrambling", JCGT 9(4)), padded as pbrt-v4's PaddedSobolSampler does. Each request a path makes (a 1D value
// or a 2D pair: the pixel position, a light's point, a BRDF direction, roulette) is a dimension of its own,
// stratified over the pixel's samples by itself: 2^k samples of a 2D request fill every elementary interval
// of area 2^-k once (a (0,2)-sequence), where independent random numbers leave holes and clumps. Each
// dimension's points are shuffled and scrambled by a hash of (pixel, seed, dimension), so that dimensions
// and pixels are uncorrelated. Like Rng, a Sampler is made from (pixel, sample index, seed), never from
// thread state, and a copy goes on in step with the original (DifferentialPathTracer's two paths).
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "core/rng.h"

namespace deltagi {

namespace sobol {

inline uint32_t reverseBits(uint32_t x) {
    x = (x << 16) | (x >> 16);
    x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);
    x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
    x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
    x = ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
    return x;
}

// A random permutation of the 32-bit values in which each bit depends on the bits below it only (Laine and
// Karras 2011, with Burley's constants): on a bit-reversed value, a nested uniform (Owen) scramble.
inline uint32_t laineKarras(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// Owen's nested uniform scramble of the 32-bit fraction x: a random permutation of each half-interval's two
// halves, at every level, chosen by `seed`.
inline uint32_t owenScramble(uint32_t x, uint32_t seed) {
    return reverseBits(laineKarras(reverseBits(x), seed));
}

// The first two Sobol' dimensions of point `index`, as 32-bit fractions: van der Corput's radical inverse,
// and the dimension whose generator matrix is Pascal's triangle mod 2 (each direction v_k = v_(k-1) ^
// v_(k-1) >> 1). Together a (0,2)-sequence in base 2.
inline uint32_t dimension0(uint32_t index) {
    return reverseBits(index);
}
inline uint32_t dimension1(uint32_t index) {
    uint32_t x = 0;
    for (uint32_t v = 0x80000000u; index != 0; index >>= 1, v ^= v >> 1)
        if (index & 1u) x ^= v;
    return x;
}

// A 32-bit fraction as a float in [0, 1): its top 24 bits, so that the largest value stays below 1.
inline float toUnit(uint32_t x) {
    return static_cast<float>(x >> 8) * 0x1p-24f;
}

}  // namespace sobol

class Sampler {
  public:
    // The samples of pixel `pixel` for `seed`; `sample` is the sample's index among the pixel's (0, 1, 2,
    // ...): the stratification holds over consecutive indices from 0.
    Sampler(uint64_t pixel, uint64_t sample, uint64_t seed)
        : stream_(mixBits(pixel ^ mixBits(seed + 0x9e3779b97f4a7c15ull))), index_(static_cast<uint32_t>(sample)) {}

    // The next dimension's value in [0, 1).
    float uniform() {
        const uint32_t shuffled = sobol::owenScramble(index_, hash(0));
        const float value = sobol::toUnit(sobol::owenScramble(sobol::dimension0(shuffled), hash(1)));
        ++dimension_;
        return value;
    }

    // The next dimension's pair in [0, 1)^2.
    glm::vec2 uniform2() {
        const uint32_t shuffled = sobol::owenScramble(index_, hash(0));
        const glm::vec2 value(sobol::toUnit(sobol::owenScramble(sobol::dimension0(shuffled), hash(1))),
                              sobol::toUnit(sobol::owenScramble(sobol::dimension1(shuffled), hash(2))));
        ++dimension_;
        return value;
    }

  private:
    // A seed for this pixel's current dimension, one per use `k`.
    uint32_t hash(uint32_t k) const {
        return static_cast<uint32_t>(mixBits(stream_ ^ mixBits((static_cast<uint64_t>(dimension_) << 2) | k)));
    }

    uint64_t stream_;
    uint32_t index_;
    uint32_t dimension_ = 0;
};

}  // namespace deltagi
