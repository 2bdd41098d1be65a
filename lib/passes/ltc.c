/* The specular lobe's linearly transformed cosines: tools/ltcfit.c fits them to rb_ggx and
 * writes ltc_ggx.inc (make ltc-table); tests/unit/test_ltc.c holds them to the lobe's integral
 * over polygons and refits some of them. */
#include "passes/passes.h"

const float rb_pass_ltc_ggx[RB_LTC_SIZE * RB_LTC_SIZE * 4] = {
#include "passes/ltc_ggx.inc"
};
