/*
 * The model a diagnosis chose (pimodel.diagnosis.model.DiagnosedModel), streamed sample by
 * sample: the PI hysteresis of a radius grid with signed weights and, in parallel, the effect
 * terms the diagnosis fitted jointly with it.  One implementation for the python-control block
 * (DiagnosedModel.block), the Python runner (pimodel.diagnosis.native_model) and the DiagnosedModel
 * FMU unit (pim_unit.h, unit 8).
 *
 * Discrete-time semantics, sample k at time t[k], input v[k], plays at rest at z_i[-1] (the
 * state, normally 0; with plays_start = 1, v[0], set on the first sample):
 *
 *     z_i[k] = max(v[k] - r_i, min(v[k] + r_i, z_i[k-1]))              plays (pim_core.h)
 *     h[k]   = sum_i w_i z_i[k],   h0[k] = sum_i w0_i z_i[k] + c0
 *
 * With a prefilter (nw > 0, a Wiener model: pimodel.diagnosis.wiener), the hysteresis term h
 * is that of the filtered input, while h0 and the effect terms keep the plays of v:
 *
 *     x_f[k]  = F_nw[... F_1[v] ...][k]    sections F_j = wf_b_j(z^-1) / wf_a_j(z^-1) in series
 *                                          (transposed DF-II, a_0 = 1), each at rest around its
 *                                          own first input (F_1: v[0])
 *     zf_i[k] = max(x_f[k] - r_i, min(x_f[k] + r_i, zf_i[k-1]))    a second play set, zf_i[-1]
 *                                          the same initial state as z_i[-1]
 *     h[k]    = sum_i w_i zf_i[k]          (instead of sum_i w_i z_i[k])
 *     x[k]   = LTI[h][k]          b(z^-1) / a(z^-1), a_0 = 1, at rest around h[0]
 *            + sum_j g_j (E_j[h0][k] - M_1[h0][k])   the linear part's further elements:
 *                                     E_j, M_1 second-order sections (b, a of 3 values each,
 *                                     a_0 = 1), at rest around h0[0] (pimodel.diagnosis.lti)
 *     y[k]   = (1 - f) x[k - d0] + f x[k - d0 - 1] + c               delay d = d0 + f samples,
 *                                                                    x[j < 0] = x[0]
 * and in the effect terms below h0[k] stands for h0 delayed alike, (1 - f) h0[k - d0] +
 * f h0[k - d0 - 1] (h0[j < 0] = h0[0]; the delay acts on the input of all the plays drive):
 *            + sum_j g_j (L_j[k] - h0[k])     creep: L_j[k] = a_j L_j[k-1] + (1 - a_j) h0[k],
 *                                                    L_j[-1] = h0[0] (lag_start NULL) or
 *                                                    L_j[-1] = lag_start[j] (a common rest:
 *                                                    pimodel.diagnosis.creep)
 *              - sum_j g_j L_j[-1]                when lag_record = 1: the creep counted from
 *                                                 the record's start (creep_start "record"),
 *                                                 L_j[-1] as above; y[0] holds no creep
 *            + q u^2 + c3 u^3,  u = (h0[k] - center) / half            asymmetry
 *            + sum_i g_i m_i[k]                 rate, radius family       (g_i: the gain
 *            + rho_f[k] sum_i g_i w0_i z_i[k]   or weight family           of play i's band)
 *            + s (t[k] - t[0])  or  s t[k]                              drift (record/absolute)
 *            + D (1 - exp(-(t[k] - t_s) / T))     a settling drift on the shared clock, when
 *                                                 T > 0 (pimodel.diagnosis.drift, "settle")
 *
 * Rate (pimodel.diagnosis.rate): rho[k] = |v[k] - v[k-1]| / dt / rate_scale (rho[0] = 0);
 * tau = rate_tau > 0: rho_f[k] = a rho_f[k-1] + (1 - a) rho[k], a = exp(-dt / tau), from
 * rho_f[-1] = 0; tau = 0: rho_f[k] = rho[k], or 0 when |v[k] - v[k-1]| > PIM_DIAG_STEP_SHARE *
 * input_range (a sampled step has no rate); rate_saturation S > 0: rho_f[k] in the terms below
 * is rho_f[k] / (1 + rho_f[k] / S) (the filter's state stays unsaturated).  Scaled family
 * (rate_family 2, the exact shape): plays zs_i of radii r_i (1 + G s[k] / (1 + s[k] / S))
 * (S = 0: G s[k]), s[k] the strictly causal filtered rate of pim_rdpi_sat_run
 * (pim_rate_dependent.h, normalised: s[k] = a s[k-1] + (1 - a) |v[k-1] - v[k-2]| / dt /
 * rate_scale, rate_tau > 0), zs_i[-1] = z_i[-1], and the term sum_i g_i w_i (zs_i[k] -
 * z_i[k]) (the weights w: the hysteresis is that of the scaled plays).  Radius family: m_i[k] = -(v[k] - z_i[k]) rho_f[k]
 * while play i (r_i > 0) is in contact (|v[k] - z_i[k]| >= r_i (1 - 1e-9)), else m_i[k-1]
 * (m_i = 0 before its first contact): the term held at the play's last contact.
 * A fractional delay part f <= 1e-12 counts as 0 (as pimodel.diagnosis.effects.shift).
 *
 * State (one flat array of pim_diag_state_size(d) doubles, so that python-control blocks and FMU
 * states hold it as is): [started, v_prev, t_start, head, z[n], rate[n_rate], L[m], s[order],
 * e[n_e], buf[nbuf], hbuf[nbuf], zf[n_f], f[2 nw], L0[n_r]] (e: two states per section M_1, E_1..E_ne, n_e =
 * 2 (ne + 1), or 0 when ne = 0; zf: the plays of the filtered input and f: two states per
 * prefilter section, n_f = n, both present only when nw > 0; L0: the lags' start h0[0], set on
 * the first sample, n_r = 1 when lag_record = 1 and m > 0, else 0) with rate = [rho_f[k-1], m[n]]
 * (radius family), [rho_f[k-1]] (weight family), [rate[k+1], zs[n]]
 * (scaled family: the rate pim_rdpi_sat_run holds for the next sample, in input unit / s, and
 * the scaled plays) or none; all zero (except z and zf = the
 * initial play states, pim_diag_initial_state) before the first sample.  `head` is the
 * ring position of x[k-1] in buf and of h0[k-1] in hbuf (nbuf = floor(d) + 2 when d > 0, else
 * 0).  Units: v and r
 * in the input unit, y, c, c0, center, half in the output unit, t in s, s in output unit / s.
 */
#ifndef PIM_DIAGNOSED_H
#define PIM_DIAGNOSED_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PIM_DIAG_STEP_SHARE 0.05     /* pimodel.diagnosis.rate.STEP_SHARE */
#define PIM_DIAG_RATE_RADIUS 0       /* rate_family: radii growing with the rate */
#define PIM_DIAG_RATE_WEIGHT 1       /* rate_family: weights growing with the rate */
#define PIM_DIAG_RATE_SCALED 2       /* rate_family: plays whose radii scale (exact shape) */
#define PIM_DIAG_HEADER 4            /* started, v_prev, t_start, head */
#define PIM_DIAG_STATE_MAX (PIM_DIAG_HEADER + 2 * PIM_DIAG_MAX_PLAYS + 1 + PIM_DIAG_MAX_LAGS + \
                            PIM_DIAG_MAX_ORDER + 2 * (PIM_DIAG_MAX_ELEMENTS + 1) + \
                            2 * PIM_DIAG_MAX_DELAY + PIM_DIAG_MAX_PLAYS + \
                            2 * PIM_DIAG_MAX_ELEMENTS + 1)

typedef struct {
    size_t n;              /* plays */
    const double *w;       /* weights w_i (any sign) */
    const double *r;       /* radii, 0 <= r_1 <= ... <= r_n */
    const double *w0;      /* reference weights w0_i (of h0) */
    double c, c0;          /* offset and reference offset */
    size_t m;              /* creep lags (0: none) */
    const double *lag_a;   /* a_j = exp(-dt / tau_j) */
    const double *lag_g;   /* gains g_j */
    int asym;              /* 0: no asymmetry term */
    double q, c3, center, half;
    const double *rate_w;  /* per play the gain g_i of its band, or NULL: no rate term */
    double dt, rate_scale, input_range;
    int rate_family;       /* PIM_DIAG_RATE_RADIUS, _WEIGHT or _SCALED */
    double rate_tau;       /* low-pass time constant of the rate [s], >= 0 (0: none) */
    double rate_saturation; /* S > 0: the rate enters as rho_f / (1 + rho_f / S); 0: linear */
    double rate_growth;    /* G of the scaled family (radii r_i (1 + G s / (1 + s / S))) */
    size_t order;          /* LTI order (0: none) */
    const double *b, *a;   /* b[0..order], a[0..order], a[0] = 1 */
    double delay;          /* d >= 0 [samples] */
    int drift_clock;       /* 0 none, 1 record (t - t[0]), 2 absolute (t) */
    double drift;          /* s */
    size_t ne;             /* further elements E_j of the linear part (0: none) */
    const double *el_b, *el_a; /* (ne + 1) sections of PIM_DIAG_SECTION coefficients: section 0
                                  the base mode M_1 on h0, section j the element E_j */
    const double *el_g;    /* gains g_j of E_1..E_ne */
    size_t nw;             /* prefilter sections F_j before the plays (0: none, a Wiener model
                              has <= PIM_DIAG_MAX_ELEMENTS) */
    const double *wf_b, *wf_a; /* nw sections of PIM_DIAG_SECTION coefficients, a[0] = 1 */
    int plays_start;       /* 0: the plays start at the initial state's z (and zf); 1: at rest
                              at the first input, z_i[-1] = v[0] (zf_i[-1] = x_f[0]), as the
                              diagnosis' nominal (pimodel.diagnosis.effects.make_segment) */
    double settle;         /* D: the settling's total change from t_s on [output unit] */
    double settle_tau;     /* T [s] (0: no settling term; else > 0) */
    double settle_t0;      /* t_s [s], on the clock t[k] */
    const double *lag_start; /* NULL: each creep lag at rest at h0[0]; else L_j[-1] =
                                lag_start[j], the lags' common rest levels (creep_start
                                "common" of pimodel.diagnosis.creep) [output unit] */
    int lag_record;        /* 0: the creep term sum_j g_j (L_j[k] - h0[k]); 1: less
                              sum_j g_j L_j[-1], the creep counted from each record's start
                              (creep_start "record" of pimodel.diagnosis.creep) */
} pim_diag;

/* Length of the flat state of d (the layout above). */
PIM_API size_t pim_diag_state_size(const pim_diag *d);

/* Length of the further elements' state: 2 (ne + 1), or 0 when ne = 0. */
PIM_API size_t pim_diag_element_states(const pim_diag *d);

/* Length of the prefilter's state: n + 2 nw (zf and the sections), or 0 when nw = 0. */
PIM_API size_t pim_diag_prefilter_states(const pim_diag *d);

/* Length of the record start's state: 1 when lag_record = 1 and m > 0, else 0. */
PIM_API size_t pim_diag_record_states(const pim_diag *d);

/* Length of the rate state: 1 + n (radius or scaled family), 1 (weight family) or 0. */
PIM_API size_t pim_diag_rate_size(const pim_diag *d);

/* Delay line length for a delay of `delay` samples: floor(delay) + 2, or 0 for delay == 0. */
PIM_API size_t pim_diag_delay_length(double delay);

/*
 * NULL when the parameters are valid (finite; radii sorted >= 0; where used: half > 0,
 * rate_scale > 0, rate_family 0, 1 or 2, rate_tau >= 0 (> 0 and rate_growth finite for 2),
 * input_range > 0 when rate_tau = 0; lags
 * 0 < a_j < 1; a[0] = 1 and sum a != 0 so that a rest state exists, for the LTI and for each
 * section of the further elements and of the prefilter; ne, nw <= PIM_DIAG_MAX_ELEMENTS;
 * 0 <= delay <= PIM_DIAG_MAX_DELAY - 2; drift_clock 0..2; settle_tau >= 0; lag_start finite;
 * lag_record 0 or 1),
 * else a static message naming the first bad one
 * (the FMU adds the value).
 */
PIM_API const char *pim_diag_check(const pim_diag *d);
/* (plays_start must be 0 or 1.) */

/* The state before the first sample into x (pim_diag_state_size(d) values): all zero, the plays
 * z (and zf) at z0 (replaced by v[0] on the first sample when plays_start = 1). */
PIM_API void pim_diag_initial_state(const pim_diag *d, double *x, double z0);

/* One sample: y[k] for v[k] at time t[k]; the state x advances to after sample k. */
PIM_API double pim_diag_step(const pim_diag *d, double *x, double v, double t);

/* After a step, with a delay: whether what the step wrote into the delay lines (the hysteresis
 * term x[k], h0[k] and the asymmetry of h0[k]) is finite: it reaches the output d samples
 * later, so a unit refuses the step that overflows, not a later one.  1 without a delay. */
PIM_API int pim_diag_pending_finite(const pim_diag *d, const double *x);

/* N samples (t may be NULL: t[k] = k dt); x advances. */
PIM_API void pim_diag_run(const pim_diag *d, double *x, size_t N, const double *v,
                          const double *t, double *y);

#ifdef __cplusplus
}
#endif

#endif /* PIM_DIAGNOSED_H */
