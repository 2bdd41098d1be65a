/* The reference's random numbers: a counter-based hash of (frame, pixel, sample, dimension), so
 * every number is independent of the thread that draws it and of the order of drawing. It is
 * deliberately not a low-discrepancy sequence: the error falls like 1/sqrt(spp), which is what
 * the convergence checks expect of a ground truth. */
#include "reference/reference_int.h"

/* SplitMix64's finalizer (Steele, Lea and Flood 2014, constants of Stafford's variant 13): a
 * bijection of 64 bits with full avalanche. */
static inline uint64_t mix64(uint64_t z)
{
    z ^= z >> 30;
    z *= 0xbf58476d1ce4e5b9ull;
    z ^= z >> 27;
    z *= 0x94d049bb133111ebull;
    z ^= z >> 31;
    return z;
}

#define GOLDEN 0x9e3779b97f4a7c15ull

uint64_t rb_ref_rand_key(uint32_t frame, uint32_t pixel, uint32_t sample)
{
    uint64_t h = mix64((((uint64_t)frame << 32) | pixel) + GOLDEN);
    return mix64(h ^ mix64((uint64_t)sample * 0xd1b54a32d192ed03ull + 0x632be59bd9b4e019ull));
}

float rb_ref_rand(uint64_t key, uint32_t dim)
{
    /* A SplitMix64 stream seeded by the key: the dim-th output. */
    uint64_t h = mix64(key + ((uint64_t)dim + 1) * GOLDEN);
    return (float)(h >> 40) * 0x1p-24f; /* 24 bits: exactly representable, < 1 */
}

float rb_reference_random(uint32_t frame, uint32_t pixel, uint32_t sample, uint32_t dim)
{
    return rb_ref_rand(rb_ref_rand_key(frame, pixel, sample), dim);
}
