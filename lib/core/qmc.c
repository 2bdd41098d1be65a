/* Hashing for random numbers and the quasi-Monte Carlo points built on it: the 2D Sobol
 * (0,2)-sequence, Owen-scrambled by a hash and with its index shuffled by another (Burley 2020,
 * "Practical Hash-based Owen Scrambling"). Pure functions of their inputs, so any thread may
 * draw any number in any order. No tables: two dimensions need none. */
#include "core/core.h"

uint64_t rb_mix64(uint64_t z)
{
    /* SplitMix64's finalizer (Steele, Lea and Flood 2014; Stafford's variant 13) */
    z ^= z >> 30;
    z *= 0xbf58476d1ce4e5b9ull;
    z ^= z >> 27;
    z *= 0x94d049bb133111ebull;
    z ^= z >> 31;
    return z;
}

static uint32_t reverse_bits(uint32_t x)
{
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

/* An Owen scramble in bit-reversed order: every step changes a bit only as a function of the
 * bits below it (xor with an even multiple, add, multiply by an odd number), so each output bit
 * depends on the seed and the less significant input bits alone, and the map is a bijection.
 * Burley's Laine-Karras hash with Vegdahl's 2021 constants, which mix better (as in Cycles). */
static uint32_t lk_hash(uint32_t x, uint32_t seed)
{
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

/* Sobol's second dimension (primitive polynomial x + 1) has Pascal's triangle mod 2 for its
 * generator matrix: bit r of point i (weight 2^-(r+1)) is the parity of the sum over the bits c
 * of i of C(c, r), odd exactly when r's bits are a subset of c's (Lucas). That is the subset
 * transform over the bit positions, five butterfly steps; the result is in bit-reversed order
 * (bit r holds weight 2^-(r+1)). */
static uint32_t pascal(uint32_t i)
{
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    i ^= (i >> 16) & 0x0000ffffu;
    return i;
}

uint32_t rb_qmc_owen(uint32_t x, uint32_t seed)
{
    return reverse_bits(lk_hash(reverse_bits(x), seed));
}

uint32_t rb_qmc_sobol(uint32_t index, uint32_t dim)
{
    if (dim == 0)
        return reverse_bits(index);
    if (dim != 1)
        RB_BUG("sobol dimension %u: only 0 and 1 exist", dim);
    return reverse_bits(pascal(index));
}

void rb_qmc_point2(uint64_t stream, uint32_t index, uint32_t out[2])
{
    /* Three independent 32-bit seeds from the stream's 64 bits. */
    uint64_t h = rb_mix64(stream);
    uint32_t seed_index = (uint32_t)h, seed_x = (uint32_t)(h >> 32);
    uint32_t seed_y = (uint32_t)rb_mix64(h);
    /* The shuffle maps each aligned block of 2^k indices onto one aligned block, so the
     * first 2^k samples (and every pass of 2^k aligned samples) remain a (0,k,2)-net. */
    uint32_t i = rb_qmc_owen(index, seed_index);
    /* Both dimensions come out of the generator bit-reversed, which is the order the scramble
     * works in: no reversing twice. */
    out[0] = reverse_bits(lk_hash(i, seed_x));
    out[1] = reverse_bits(lk_hash(pascal(i), seed_y));
}

float rb_qmc_float(uint32_t x)
{
    return (float)(x >> 8) * 0x1p-24f; /* 24 bits: exactly representable, < 1 */
}
