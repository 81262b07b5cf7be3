/* Rate-dependent PI operator and its exact inverse; semantics in pim_rate_dependent.h. */
#include "pim_rate_dependent.h"

#include "pim_asymmetric.h"
#include "pim_generalized.h"

#include <math.h>

double pim_play_solve(size_t n, const double *p, const double *r, double *z, double y)
{
    /* the asymmetric operator's solve with gamma_l = gamma_r = s and no direct term */
    const pim_asym plain = {0.0, 1.0, 0.0, 1.0, 0.0, PIM_ENV_POLY2, {0.0, 1.0, 0.0, 0.0},
                            PIM_ENV_POLY2_INV};
    if (n == 0 || n > PIM_MAX_PLAYS) return NAN;
    const double v = pim_asym_solve(&plain, n, p, r, z, y);
    (void)pim_pi_step(n, p, r, z, v);
    return v;
}

/* hist = (v[k-1], rate[k]) -> (v[k], rate[k+1]) */
static void rate_update(double *hist, double v, double lam, double Ts)
{
    hist[1] = lam * hist[1] + (1.0 - lam) * fabs(v - hist[0]) / Ts;
    hist[0] = v;
}

/* the radii's relative growth g at the rate hist[1]: r_i = alpha_i + alpha_i g */
static double rate_growth(const double *hist, double beta, double sat)
{
    return sat > 0.0 ? beta * hist[1] / (1.0 + hist[1] / sat) : beta * hist[1];
}

/* one play of radius alpha_i (1 + g) at the input v (alpha_1 = 0 stays 0) */
static double rate_play(double z, double alpha_i, double g, double v)
{
    const double ri = alpha_i + alpha_i * g;
    const double zi = z < v + ri ? z : v + ri;
    return zi > v - ri ? zi : v - ri;
}

void pim_rdpi_run(size_t N, size_t n, const double *p, const double *alpha, double beta,
                  double lam, double Ts, double *z, double *hist, const double *v, double *y)
{
    pim_rdpi_sat_run(N, n, p, alpha, beta, 0.0, lam, Ts, z, hist, v, y);
}

void pim_rdpi_sat_run(size_t N, size_t n, const double *p, const double *alpha, double beta,
                      double sat, double lam, double Ts, double *z, double *hist,
                      const double *v, double *y)
{
    for (size_t k = 0; k < N; ++k) {
        double acc = 0.0;
        const double g = rate_growth(hist, beta, sat);
        for (size_t i = 0; i < n; ++i) {
            z[i] = rate_play(z[i], alpha[i], g, v[k]);
            acc += p[i] * z[i];
        }
        y[k] = acc;
        rate_update(hist, v[k], lam, Ts);
    }
}

void pim_rdpi_sat_plays_strided(size_t N, size_t n, const double *alpha, double beta,
                                double sat, double lam, double Ts, double *z, double *hist,
                                const double *v, double *zs, size_t ks, size_t is)
{
    for (size_t k = 0; k < N; ++k) {
        const double g = rate_growth(hist, beta, sat);
        for (size_t i = 0; i < n; ++i)
            zs[k * ks + i * is] = z[i] = rate_play(z[i], alpha[i], g, v[k]);
        rate_update(hist, v[k], lam, Ts);
    }
}

void pim_rdpi_sat_plays(size_t N, size_t n, const double *alpha, double beta, double sat,
                        double lam, double Ts, double *z, double *hist, const double *v,
                        double *zs)
{
    pim_rdpi_sat_plays_strided(N, n, alpha, beta, sat, lam, Ts, z, hist, v, zs, n, 1);
}

int pim_rdpi_inverse_run(size_t N, size_t n, const double *p, const double *alpha, double beta,
                         double lam, double Ts, double *z, double *hist, const double *yd,
                         double *v)
{
    double rl[PIM_MAX_PLAYS];
    if (n > PIM_MAX_PLAYS) return -1;
    for (size_t k = 0; k < N; ++k) {
        for (size_t i = 0; i < n; ++i) rl[i] = alpha[i] + alpha[i] * beta * hist[1];
        v[k] = pim_play_solve(n, p, rl, z, yd[k]);
        rate_update(hist, v[k], lam, Ts);
    }
    return 0;
}
