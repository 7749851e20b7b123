/* SPDX-License-Identifier: BSD-3-Clause */
/* Deterministic random numbers for tests (xoshiro256** seeded by splitmix64). */
#ifndef CYL_TEST_RNG_H
#define CYL_TEST_RNG_H
#include <stdint.h>

typedef struct test_rng { uint64_t s[4]; int have_spare; double spare; } test_rng;

void test_rng_seed(test_rng *r, uint64_t seed);
uint64_t test_rng_u64(test_rng *r);
/* Uniform integer in [lo, hi] (inclusive). */
int64_t test_rng_int(test_rng *r, int64_t lo, int64_t hi);
/* Uniform double in [0, 1). */
double test_rng_uniform(test_rng *r);
/* Standard normal (polar Box-Muller). */
double test_rng_normal(test_rng *r);
#endif
