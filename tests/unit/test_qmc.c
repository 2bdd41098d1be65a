/* lib/core's quasi-Monte Carlo points: the Sobol generator against its definition, the Owen
 * scramble's nesting, stratification of the scrambled and shuffled 2D sequence in every aligned
 * block, determinism, uniformity over streams, and the convergence it buys on smooth and
 * discontinuous integrands against independent (hashed) numbers. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "core/core.h"

/* Sobol's second dimension from its generator matrix, written independently of qmc.c: bit r
 * (weight 2^-(r+1)) of point i is the parity of sum_c bit_c(i) C(c, r), and C(c, r) is odd
 * exactly when r's bits are a subset of c's (Lucas). */
static uint32_t sobol1_by_matrix(uint32_t i)
{
    uint32_t x = 0;
    for (uint32_t r = 0; r < 32; r++) {
        uint32_t parity = 0;
        for (uint32_t c = 0; c < 32; c++)
            if ((i >> c) & 1u)
                parity ^= (r & c) == r;
        x |= parity << (31 - r);
    }
    return x;
}

static void test_sobol(void **state)
{
    (void)state;
    for (uint32_t i = 0; i < 4096; i++) {
        uint32_t rev = 0;
        for (int b = 0; b < 32; b++)
            rev |= ((i >> b) & 1u) << (31 - b);
        assert_int_equal(rb_qmc_sobol(i, 0), rev);
        assert_int_equal(rb_qmc_sobol(i, 1), sobol1_by_matrix(i));
    }
    for (uint32_t k = 0; k < 32; k++) { /* every single bit, up to the last */
        uint32_t i = 1u << k;
        assert_int_equal(rb_qmc_sobol(i, 1), sobol1_by_matrix(i));
        assert_int_equal(rb_qmc_sobol(~0u >> k, 1), sobol1_by_matrix(~0u >> k));
    }
    /* the unscrambled start of the sequence */
    assert_int_equal(rb_qmc_sobol(1, 1), 0x80000000u);
    assert_int_equal(rb_qmc_sobol(2, 1), 0xc0000000u);
    assert_int_equal(rb_qmc_sobol(3, 1), 0x40000000u);
}

/* Fractions that share their first k bits still do after the scramble; the scramble is a
 * bijection (on every prefix length), and the seed matters. */
static void test_owen(void **state)
{
    (void)state;
    uint64_t h = 12345;
    for (int n = 0; n < 20000; n++) {
        h = rb_mix64(h + 1);
        uint32_t x = (uint32_t)h, seed = (uint32_t)(h >> 32), k = (uint32_t)(h >> 27) % 33;
        uint32_t mask = k ? ~0u << (32 - k) : 0u;
        uint32_t y = (x & mask) | ((uint32_t)rb_mix64(h) & ~mask);
        uint32_t sx = rb_qmc_owen(x, seed), sy = rb_qmc_owen(y, seed);
        if ((sx & mask) != (sy & mask))
            fail_msg("%08x and %08x share %u bits, scrambled %08x and %08x do not", x, y, k, sx,
                     sy);
    }
    /* a permutation of the 2^16 16-bit prefixes */
    uint8_t *seen = calloc(1u << 16, 1);
    assert_non_null(seen);
    for (uint32_t i = 0; i < (1u << 16); i++)
        seen[rb_qmc_owen(i << 16, 0x9e3779b9u) >> 16]++;
    for (uint32_t i = 0; i < (1u << 16); i++)
        assert_int_equal(seen[i], 1);
    free(seen);
    uint32_t same = 0;
    for (uint32_t i = 0; i < 1000; i++)
        same += rb_qmc_owen(i * 0x01000193u, 1) == rb_qmc_owen(i * 0x01000193u, 2);
    assert_true(same < 5);
}

/* Exactly one point of points [first, first + 2^k) in every elementary interval of area 2^-k
 * (2^a columns by 2^(k-a) rows, for every a). */
static void check_net(uint64_t stream, uint32_t first, int k)
{
    uint32_t n = 1u << k;
    uint32_t(*pts)[2] = malloc(n * sizeof(*pts));
    uint32_t *cells = malloc(n * sizeof(uint32_t));
    assert_non_null(pts);
    assert_non_null(cells);
    for (uint32_t i = 0; i < n; i++)
        rb_qmc_point2(stream, first + i, pts[i]);
    for (int a = 0; a <= k; a++) {
        memset(cells, 0, n * sizeof(uint32_t));
        for (uint32_t i = 0; i < n; i++) {
            uint32_t cx = a ? pts[i][0] >> (32 - a) : 0,
                     cy = k - a ? pts[i][1] >> (32 - (k - a)) : 0;
            cells[(cx << (k - a)) | cy]++;
        }
        for (uint32_t c = 0; c < n; c++)
            if (cells[c] != 1)
                fail_msg("stream %llu, points %u-%u, %d x %d cells: cell %u has %u",
                         (unsigned long long)stream, first, first + n - 1, 1 << a, 1 << (k - a), c,
                         cells[c]);
    }
    free(cells);
    free(pts);
}

static void test_stratification(void **state)
{
    (void)state;
    for (uint64_t stream = 0; stream < 16; stream++)
        for (int k = 0; k <= 12; k++)
            for (uint32_t block = 0; block < 3; block++) /* the first, second and third runs */
                check_net(rb_mix64(stream), block << k, k);
    /* the renderer's passes of 1, 1, 2, 4, 8, 16, 16, ... samples: each is an aligned block */
    check_net(7, 16, 4);
    check_net(7, 32, 4);
    check_net(7, 48, 4);
    /* and the 24 bits of the floats keep it */
    uint32_t cells[64] = {0};
    for (uint32_t i = 0; i < 64; i++) {
        uint32_t p[2];
        rb_qmc_point2(99, i, p);
        float x = rb_qmc_float(p[0]), y = rb_qmc_float(p[1]);
        assert_true(x >= 0.0f && x < 1.0f && y >= 0.0f && y < 1.0f);
        cells[(int)(x * 8.0f) * 8 + (int)(y * 8.0f)]++;
    }
    for (int c = 0; c < 64; c++)
        assert_int_equal(cells[c], 1);
}

static void test_determinism(void **state)
{
    (void)state;
    enum { N = 1024 };
    uint32_t fwd[N][2];
    for (uint32_t i = 0; i < N; i++)
        rb_qmc_point2(0xabcdefull, i, fwd[i]);
    for (uint32_t i = N; i-- > 0;) { /* another order gives the same points */
        uint32_t p[2];
        rb_qmc_point2(0xabcdefull, i, p);
        assert_memory_equal(p, fwd[i], sizeof(p));
    }
    /* another stream, other points (and distinct points within a stream) */
    uint32_t same = 0, dup = 0;
    for (uint32_t i = 0; i < N; i++) {
        uint32_t p[2];
        rb_qmc_point2(0xabcdeeull, i, p);
        same += p[0] == fwd[i][0] || p[1] == fwd[i][1];
        dup += i > 0 && fwd[i][0] == fwd[i - 1][0];
    }
    assert_true(same < 4);
    assert_int_equal(dup, 0);
}

/* Over streams, every point of the sequence is uniform on the square (the scramble's point). */
static void test_uniform(void **state)
{
    (void)state;
    enum { STREAMS = 4096 };
    for (uint32_t i = 0; i < 8; i++) {
        double sum[2] = {0, 0};
        uint32_t bins[16] = {0};
        for (uint64_t s = 0; s < STREAMS; s++) {
            uint32_t p[2];
            rb_qmc_point2(s * 0x9e3779b97f4a7c15ull, i, p);
            sum[0] += rb_qmc_float(p[0]);
            sum[1] += rb_qmc_float(p[1]);
            bins[(p[0] >> 30) * 4 + (p[1] >> 30)]++;
        }
        /* the mean's sd is 1/sqrt(12 * 4096) = 0.0045 */
        for (int d = 0; d < 2; d++)
            if (!(fabs(sum[d] / STREAMS - 0.5) < 0.018))
                fail_msg("point %u, dimension %d: mean %g over %d streams", i, d, sum[d] / STREAMS,
                         STREAMS);
        /* 15 degrees of freedom: P(chi2 > 40) < 5e-4 */
        double chi = 0.0, e = STREAMS / 16.0;
        for (int b = 0; b < 16; b++)
            chi += (bins[b] - e) * (bins[b] - e) / e;
        if (!(chi < 40.0))
            fail_msg("point %u: chi-square %g over a 4 x 4 grid", i, chi);
    }
}

/* RMSE over many streams of the n-point estimate of the integral of f over the unit square. */
static double rmse(double (*f)(double, double), double want, uint32_t n, bool is_hashed)
{
    enum { STREAMS = 2048 };
    double sum2 = 0.0;
    for (uint64_t s = 0; s < STREAMS; s++) {
        uint64_t stream = rb_mix64(s + 77);
        double est = 0.0;
        for (uint32_t i = 0; i < n; i++) {
            uint32_t p[2];
            if (is_hashed) {
                uint64_t h = rb_mix64(stream ^ rb_mix64(i));
                p[0] = (uint32_t)h;
                p[1] = (uint32_t)(h >> 32);
            } else {
                rb_qmc_point2(stream, i, p);
            }
            est += f(rb_qmc_float(p[0]), rb_qmc_float(p[1]));
        }
        double e = est / n - want;
        sum2 += e * e;
    }
    return sqrt(sum2 / STREAMS);
}

static double smooth(double x, double y)
{
    return exp(x + y);
}

static double disc(double x, double y)
{
    return x * x + y * y < 1.0 ? 1.0 : 0.0;
}

/* Monte Carlo's RMSE falls by 0.5 from 16 to 64 points. Owen-scrambled nets reach variance
 * O(n^-3 log n) on smooth integrands (Owen 1997: a ratio near 0.125) and O(n^-1.5) where a
 * curve cuts the integrand (a ratio near 0.35). */
static void test_convergence(void **state)
{
    (void)state;
    const double e1 = exp(1.0) - 1.0, quarter = 3.14159265358979323846 / 4.0;
    double q16 = rmse(smooth, e1 * e1, 16, false), q64 = rmse(smooth, e1 * e1, 64, false);
    double h16 = rmse(smooth, e1 * e1, 16, true), h64 = rmse(smooth, e1 * e1, 64, true);
    double d16 = rmse(disc, quarter, 16, false), d64 = rmse(disc, quarter, 64, false);
    double g16 = rmse(disc, quarter, 16, true), g64 = rmse(disc, quarter, 64, true);
    print_message("# RMSE 16, 64 points: smooth: sobol %.3g %.3g (%.3f), hashed %.3g %.3g "
                  "(%.3f); disc: sobol %.3g %.3g (%.3f), hashed %.3g %.3g (%.3f)\n",
                  q16, q64, q64 / q16, h16, h64, h64 / h16, d16, d64, d64 / d16, g16, g64,
                  g64 / g16);
    /* 2048 streams estimate an RMSE within about 1.6% (more for heavy tails) */
    if (!(h64 / h16 > 0.45 && h64 / h16 < 0.55 && g64 / g16 > 0.45 && g64 / g16 < 0.55))
        fail_msg("hashed: ratios %g and %g, not 0.5", h64 / h16, g64 / g16);
    if (!(q64 / q16 < 0.2 && q64 < 0.05 * h64))
        fail_msg("smooth: sobol %g, %g against hashed %g, %g", q16, q64, h16, h64);
    if (!(d64 / d16 < 0.42 && d64 < 0.5 * g64 && d16 < g16))
        fail_msg("disc: sobol %g, %g against hashed %g, %g", d16, d64, g16, g64);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sobol),          cmocka_unit_test(test_owen),
        cmocka_unit_test(test_stratification), cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_uniform),        cmocka_unit_test(test_convergence),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
