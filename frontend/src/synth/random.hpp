// SPDX-License-Identifier: BSD-3-Clause
// Helpers internal to frontend/src/synth/: seeded random streams (splitmix64, and a
// standard-normal stream by Box-Muller on its outputs; deterministic for a seed) and angle
// wrapping.
#pragma once
#include <cmath>
#include <cstdint>

namespace cylfe {
namespace synth {
namespace detail {

inline uint64_t splitmix(uint64_t &x)
{
    uint64_t z = (x += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

struct NormalStream {
    uint64_t st;
    explicit NormalStream(uint64_t seed) : st(seed) {}
    double uni() { return ((splitmix(st) >> 11) + 0.5) * (1.0 / 9007199254740992.0); }
    double normal() { return std::sqrt(-2 * std::log(uni())) * std::cos(2 * 3.14159265358979323846 * uni()); }
    double operator()() { return normal(); }
};

// Angle wrapped to (-pi, pi].
inline double wrap(double a)
{
    const double pi = 3.14159265358979323846;
    while (a > pi) a -= 2 * pi;
    while (a <= -pi) a += 2 * pi;
    return a;
}

} // namespace detail
} // namespace synth
} // namespace cylfe
