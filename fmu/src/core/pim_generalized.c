/* Generalized PI operator and envelope functions; semantics in pim_generalized.h. */
#include "pim_generalized.h"

#include <math.h>

/* static so that the run loop inlines it (exported functions may be interposed under -fPIC) */
static inline double envelope(int kind, const double *c, double x)
{
    switch (kind) {
    case PIM_ENV_POLY2:
        if (!(c[1] + 2.0 * c[2] * x > 0.0)) return NAN;
        return c[0] + x * (c[1] + c[2] * x);
    case PIM_ENV_TANH:
        return c[0] * tanh(c[1] * x + c[2]) + c[3];
    case PIM_ENV_POLY2_INV: {
        const double d = c[1] * c[1] + 4.0 * c[2] * (x - c[0]);
        if (!(d > 0.0)) return NAN;
        return 2.0 * (x - c[0]) / (c[1] + sqrt(d)); /* the root with c1 + 2 c2 f > 0 */
    }
    case PIM_ENV_TANH_INV: {
        const double s = (x - c[3]) / c[0];
        if (!(fabs(s) < 1.0)) return NAN;
        return (atanh(s) - c[2]) / c[1];
    }
    default:
        return NAN;
    }
}

double pim_envelope(int kind, const double *c, double x) { return envelope(kind, c, x); }

const char *pim_envelope_check(int kind, const double *c)
{
    const int m = (kind == PIM_ENV_TANH || kind == PIM_ENV_TANH_INV) ? 4 : 3;
    for (int i = 0; i < m; ++i) {
        if (!isfinite(c[i])) return "an envelope coefficient is not finite";
    }
    switch (kind) {
    case PIM_ENV_POLY2:
    case PIM_ENV_POLY2_INV:
        if (c[2] == 0.0 && !(c[1] > 0.0)) return "envelope c1 must be > 0 when c2 == 0";
        return NULL;
    case PIM_ENV_TANH:
    case PIM_ENV_TANH_INV:
        if (!(c[0] > 0.0)) return "envelope c0 (tanh amplitude) must be > 0";
        if (!(c[1] > 0.0)) return "envelope c1 (tanh input gain) must be > 0";
        return NULL;
    default:
        return "unknown envelope kind";
    }
}

size_t pim_gpi_run(size_t N, size_t n, const double *p, const double *r, double *z,
                   int kind_in, const double *c_in, int kind_out, const double *c_out,
                   const double *v, double *y)
{
    double zl[PIM_MAX_PLAYS];
    double *zs = n > PIM_MAX_PLAYS ? z : zl;
    if (zs != z) {
        for (size_t i = 0; i < n; ++i) zs[i] = z[i];
    }
    size_t bad = 0;
    for (size_t k = 0; k < N; ++k) {
        const double u = envelope(kind_in, c_in, v[k]);
        if (isnan(u)) {
            y[k] = NAN;
            bad = k + 1;
            break;
        }
        y[k] = envelope(kind_out, c_out, pim_pi_step_inline(n, p, r, zs, u));
        if (isnan(y[k])) {
            bad = k + 1;
            break;
        }
    }
    if (zs != z) {
        for (size_t i = 0; i < n; ++i) z[i] = zs[i];
    }
    return bad;
}
