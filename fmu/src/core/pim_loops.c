/* Compiled closed-loop paths; semantics in pim_loops.h. */
#include "pim_loops.h"

#include <math.h>
#include <string.h>

double pim_adaptive_inverse_step(size_t n, const double *p, const double *r, double *zm,
                                 double yd)
{
    double pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS], zinv[PIM_MAX_PLAYS];
    if (n > PIM_MAX_PLAYS || pim_pi_inverse(n, p, r, zm, pinv, rinv, zinv) != 0) return NAN;
    double v = pim_pi_step(n, pinv, rinv, zinv, yd);
    (void)pim_pi_step(n, p, r, zm, v);
    return v;
}

size_t pim_loop_sizeof(void) { return sizeof(pim_loop); }

int pim_loop_run(pim_loop *L, size_t N, const double *ref, double *y, double *v, double *e,
                 double *R)
{
    for (size_t k = 0; k < N; ++k) {
        const double rk = ref[k];
        double yk_state = 0.0;
        for (size_t i = 0; i < L->nx; ++i) yk_state += L->C[i] * L->xd[i];
        double rhat[PIM_MAX_PLAYS];
        double ff;
        if (L->ff_mode == 1) {
            ff = pim_pi_step(L->ni, L->pinv, L->rinv, L->zinv, rk);
        } else if (L->ff_mode == 2) {
            memcpy(rhat, L->est.rhat, L->nm * sizeof(double));
            if (R) memcpy(R + k * L->nm, rhat, L->nm * sizeof(double));
            ff = pim_adaptive_inverse_step(L->nm, L->pm, rhat, L->zm, rk);
            if (isnan(ff)) return -1;
        } else {
            ff = L->ff_gain * rk;
        }
        double u = 0.0, ek = 0.0;
        if (L->pid_on) {
            ek = rk - yk_state;
            L->integ += L->dt * ek;
            L->dfilt = (L->tf * L->dfilt + L->kd * (ek - L->e_prev)) / (L->tf + L->dt);
            L->e_prev = ek;
            u = L->kp * ek + L->ki * L->integ + L->dfilt;
        }
        const double vk = ff + u;
        const double h = pim_pi_step(L->n, L->p, L->r, L->z, vk);
        double yk = h;
        if (L->nx > 0) {
            yk = yk_state + L->D * h;
            double xn[PIM_MAX_DYN];
            for (size_t i = 0; i < L->nx; ++i) {
                double acc = L->B[i] * h;
                for (size_t j = 0; j < L->nx; ++j) acc += L->A[i * L->nx + j] * L->xd[j];
                xn[i] = acc;
            }
            memcpy(L->xd, xn, L->nx * sizeof(double));
        }
        if (L->ff_mode == 2) {
            double yh, err, ed;
            (void)pim_est_step(&L->est, vk, yk, NULL, &yh, &err, &ed);
        }
        y[k] = yk;
        if (v) v[k] = vk;
        if (e) e[k] = rk - yk;
    }
    return 0;
}
