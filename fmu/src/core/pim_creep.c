/* Creep operator (sum of ZOH first-order lags) and its inverse; semantics in pim_creep.h. */
#include "pim_creep.h"

static double lag_sum(size_t m, const double *c, const double *x)
{
    double s = 0.0;
    for (size_t i = 0; i < m; ++i) s += c[i] * x[i];
    return s;
}

static void lag_update(size_t m, const double *a, double *x, double u)
{
    for (size_t i = 0; i < m; ++i) x[i] = a[i] * x[i] + (1.0 - a[i]) * u;
}

void pim_creep_run(size_t N, size_t m, const double *a, const double *c, double *x,
                   const double *u, double *y)
{
    for (size_t k = 0; k < N; ++k) {
        y[k] = u[k] + lag_sum(m, c, x);
        lag_update(m, a, x, u[k]);
    }
}

void pim_creep_inverse_run(size_t N, size_t m, const double *a, const double *c, double *x,
                           const double *y, double *u)
{
    for (size_t k = 0; k < N; ++k) {
        u[k] = y[k] - lag_sum(m, c, x);
        lag_update(m, a, x, u[k]);
    }
}
