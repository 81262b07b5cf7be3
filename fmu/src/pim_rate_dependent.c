/* Rate-dependent PI operator and its exact inverse; semantics in pim_rate_dependent.h. */
#include "pim_rate_dependent.h"

#include <math.h>

static double play_sum(size_t n, const double *p, const double *r, const double *z, double v)
{
    double y = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double zi = z[i] < v + r[i] ? z[i] : v + r[i];
        zi = zi > v - r[i] ? zi : v - r[i];
        y += p[i] * zi;
    }
    return y;
}

double pim_play_solve(size_t n, const double *p, const double *r, double *z, double y)
{
    double b[2 * PIM_MAX_PLAYS] = {0.0};
    if (n == 0 || n > PIM_MAX_PLAYS) return NAN;
    size_t m = 0;
    double P = 0.0;
    for (size_t i = 0; i < n; ++i) {
        b[m++] = z[i] - r[i];
        b[m++] = z[i] + r[i];
        P += p[i];
    }
    for (size_t i = 1; i < m; ++i) { /* insertion sort: m <= 128 */
        const double x = b[i];
        size_t j = i;
        while (j > 0 && b[j - 1] > x) {
            b[j] = b[j - 1];
            --j;
        }
        b[j] = x;
    }
    double v;
    double f_lo = play_sum(n, p, r, z, b[0]);
    if (y <= f_lo) {
        v = b[0] - (f_lo - y) / P; /* every play on its upper bound v + r_i: slope P */
    } else {
        v = NAN;
        for (size_t j = 1; j < m; ++j) {
            const double f_hi = play_sum(n, p, r, z, b[j]);
            if (y <= f_hi) {
                v = f_hi > f_lo ? b[j - 1] + (y - f_lo) * (b[j] - b[j - 1]) / (f_hi - f_lo)
                                : b[j - 1];
                break;
            }
            f_lo = f_hi;
        }
        if (isnan(v)) v = b[m - 1] + (y - f_lo) / P; /* every play on v - r_i */
    }
    (void)pim_pi_step(n, p, r, z, v);
    return v;
}

/* hist = (v[k-1], rate[k]) -> (v[k], rate[k+1]) */
static void rate_update(double *hist, double v, double lam, double Ts)
{
    hist[1] = lam * hist[1] + (1.0 - lam) * fabs(v - hist[0]) / Ts;
    hist[0] = v;
}

void pim_rdpi_run(size_t N, size_t n, const double *p, const double *alpha, double beta,
                  double lam, double Ts, double *z, double *hist, const double *v, double *y)
{
    for (size_t k = 0; k < N; ++k) {
        const double scale = 1.0 + beta * hist[1];
        double acc = 0.0;
        for (size_t i = 0; i < n; ++i) {
            const double ri = alpha[i] * scale;
            double zi = z[i] < v[k] + ri ? z[i] : v[k] + ri;
            z[i] = zi > v[k] - ri ? zi : v[k] - ri;
            acc += p[i] * z[i];
        }
        y[k] = acc;
        rate_update(hist, v[k], lam, Ts);
    }
}

int pim_rdpi_inverse_run(size_t N, size_t n, const double *p, const double *alpha, double beta,
                         double lam, double Ts, double *z, double *hist, const double *yd,
                         double *v)
{
    double rl[PIM_MAX_PLAYS];
    if (n > PIM_MAX_PLAYS) return -1;
    for (size_t k = 0; k < N; ++k) {
        const double scale = 1.0 + beta * hist[1];
        for (size_t i = 0; i < n; ++i) rl[i] = alpha[i] * scale;
        v[k] = pim_play_solve(n, p, rl, z, yd[k]);
        rate_update(hist, v[k], lam, Ts);
    }
    return 0;
}
