// Random numbers for Monte Carlo: a PCG32 generator (O'Neill 2014) seeded by a hash of what is being sampled
// (pixel, sample index, seed), never by thread state, so that results do not depend on the thread count.
#pragma once

#include <cstdint>

namespace deltagi {

// A 64-bit mix (SplitMix64's finalizer): neighbouring inputs give unrelated outputs.
inline uint64_t mixBits(uint64_t v) {
    v ^= v >> 31;
    v *= 0x7fb5d329728ea185ull;
    v ^= v >> 27;
    v *= 0x81dadef4bc2dd44dull;
    v ^= v >> 33;
    return v;
}

class Rng {
  public:
    Rng() = default;
    // One stream per (a, b, c), e.g. (pixel index, sample index, seed).
    Rng(uint64_t a, uint64_t b, uint64_t c = 0) {
        const uint64_t seed = mixBits(a ^ mixBits(b ^ mixBits(c + 0x9e3779b97f4a7c15ull)));
        inc_ = (mixBits(seed + 1) << 1u) | 1u;
        state_ = 0;
        nextUint();
        state_ += seed;
        nextUint();
    }

    uint32_t nextUint() {
        const uint64_t old = state_;
        state_ = old * 6364136223846793005ull + inc_;
        const auto xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        const auto rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
    }

    // Uniform in [0, 1): 24 random bits, so that the largest value is strictly below 1 as a float.
    float uniform() { return static_cast<float>(nextUint() >> 8) * 0x1p-24f; }

  private:
    uint64_t state_ = 0x853c49e6748fea9bull;
    uint64_t inc_ = 0xda3e39cb94b95bdbull;
};

}  // namespace deltagi
