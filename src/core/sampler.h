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
// v_(k-1) >> 1). Together a (0,2)-sequence in base 2. The second by bytes: the XOR of the directions of each
// byte's set bits, from tables made at compile time.
inline uint32_t dimension0(uint32_t index) {
    return reverseBits(index);
}
struct Dimension1Tables {
    uint32_t byte[4][256];
    constexpr Dimension1Tables() : byte{} {
        uint32_t directions[32] = {};
        uint32_t v = 0x80000000u;
        for (uint32_t& d : directions) {
            d = v;
            v ^= v >> 1;
        }
        for (int j = 0; j < 4; ++j)
            for (int b = 0; b < 256; ++b) {
                uint32_t x = 0;
                for (int k = 0; k < 8; ++k)
                    if (b & (1 << k)) x ^= directions[8 * j + k];
                byte[j][b] = x;
            }
    }
};
inline constexpr Dimension1Tables kDimension1{};
inline uint32_t dimension1(uint32_t index) {
    return kDimension1.byte[0][index & 0xffu] ^ kDimension1.byte[1][(index >> 8) & 0xffu] ^
           kDimension1.byte[2][(index >> 16) & 0xffu] ^ kDimension1.byte[3][index >> 24];
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
        : stream_(mixBits(pixel ^ mixBits(seed + 0x9e3779b97f4a7c15ull))),
          reversedIndex_(sobol::reverseBits(static_cast<uint32_t>(sample))) {}

    // The next dimension's value in [0, 1): the shuffled index's radical inverse, scrambled. (Owen's
    // scramble of a radical inverse is the radical inverse of Laine-Karras on the index: the reversals
    // cancel.)
    float uniform() {
        const uint64_t h = hash();
        const uint32_t shuffled = shuffle(static_cast<uint32_t>(h));
        ++dimension_;
        return sobol::toUnit(
            sobol::reverseBits(sobol::laineKarras(shuffled, static_cast<uint32_t>(h >> 32))));
    }

    // The next dimension's pair in [0, 1)^2.
    glm::vec2 uniform2() {
        const uint64_t h = hash(), h2 = mixBits(h);
        const uint32_t shuffled = shuffle(static_cast<uint32_t>(h));
        ++dimension_;
        return {
            sobol::toUnit(sobol::reverseBits(sobol::laineKarras(shuffled, static_cast<uint32_t>(h >> 32)))),
            sobol::toUnit(sobol::owenScramble(sobol::dimension1(shuffled), static_cast<uint32_t>(h2)))};
    }

  private:
    // 64 bits for this pixel's current dimension.
    uint64_t hash() const {
        return mixBits(stream_ ^ (static_cast<uint64_t>(dimension_) * 0x9e3779b97f4a7c15ull));
    }
    // The sample's index after a nested uniform scramble: a permutation of the indices that keeps each
    // aligned block of 2^k of them together, so that the first 2^k samples stay stratified.
    uint32_t shuffle(uint32_t seed) const {
        return sobol::reverseBits(sobol::laineKarras(reversedIndex_, seed));
    }

    uint64_t stream_;
    uint32_t reversedIndex_;
    uint32_t dimension_ = 0;
};

}  // namespace deltagi
