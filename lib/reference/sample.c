/* The reference's random numbers, keyed by (frame, pixel, sample, dimension) so that every
 * number is independent of the thread that draws it and of the order of drawing. By default a
 * low-discrepancy sampler: dimensions 2k and 2k+1 are one 2D point of an Owen-scrambled Sobol
 * (0,2)-sequence (lib/core/qmc.c) over the samples, each pair with its own seeds and shuffled
 * index (padding), each pixel and frame with its own seed. Its error falls faster than
 * 1/sqrt(spp) where the integrand is smooth in a pair, and never more slowly (the variance of
 * scrambled nets is o(1/spp) for any square-integrable integrand, Owen 1997). The hashed
 * sampler is independent uniform numbers: plain Monte Carlo, for comparisons. */
#include "reference/reference_int.h"

#define GOLDEN 0x9e3779b97f4a7c15ull

void rb_ref_rng_init(struct rb_ref_rng *rng, bool is_hashed, uint32_t frame, uint32_t pixel,
                     uint32_t sample)
{
    uint64_t h = rb_mix64((((uint64_t)frame << 32) | pixel) + GOLDEN);
    rng->is_hashed = is_hashed;
    rng->sample = sample;
    if (is_hashed)
        h = rb_mix64(h ^
                     rb_mix64((uint64_t)sample * 0xd1b54a32d192ed03ull + 0x632be59bd9b4e019ull));
    rng->seed = h;
}

void rb_ref_rng_replicate(struct rb_ref_rng *rng, uint32_t replicate)
{
    if (replicate)
        rng->seed = rb_mix64(rng->seed ^ rb_mix64((uint64_t)replicate * GOLDEN));
}

float rb_ref_rand(const struct rb_ref_rng *rng, uint32_t dim)
{
    if (rng->is_hashed) /* a SplitMix64 stream seeded by the key: the dim-th output */
        return rb_qmc_float((uint32_t)(rb_mix64(rng->seed + ((uint64_t)dim + 1) * GOLDEN) >> 32));
    uint32_t p[2];
    rb_qmc_point2(rng->seed + ((uint64_t)(dim >> 1) + 1) * GOLDEN, rng->sample, p);
    return rb_qmc_float(p[dim & 1]);
}

void rb_ref_rand2(const struct rb_ref_rng *rng, uint32_t dim, float out[2])
{
    if (rng->is_hashed || (dim & 1)) {
        out[0] = rb_ref_rand(rng, dim);
        out[1] = rb_ref_rand(rng, dim + 1);
        return;
    }
    uint32_t p[2];
    rb_qmc_point2(rng->seed + ((uint64_t)(dim >> 1) + 1) * GOLDEN, rng->sample, p);
    out[0] = rb_qmc_float(p[0]);
    out[1] = rb_qmc_float(p[1]);
}

float rb_reference_random(uint32_t frame, uint32_t pixel, uint32_t sample, uint32_t dim)
{
    struct rb_ref_rng rng;
    rb_ref_rng_init(&rng, false, frame, pixel, sample);
    return rb_ref_rand(&rng, dim);
}
