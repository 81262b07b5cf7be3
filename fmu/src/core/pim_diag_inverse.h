/*
 * The causal feedforward of a diagnosed model (pimodel.diagnosis.model.DiagnosedInverse.block,
 * pimodel.diagnosis.reference_inverse._InverseStream) streamed sample by sample: one
 * implementation for the Python binding (pimodel.diagnosis.native_inverse) and the
 * DiagnosedInverse FMU unit (pim_unit.h, unit 9).
 *
 * Discrete-time semantics, reference sample y_d[k] in, input v[k] out (units: y_d in the
 * model's output unit, v and r in its input unit):
 *
 *     f[k]   = S_ns[... S_1[y_d] ...][k]     prefilter sections S_j = sos_j (b0 b1 b2 a0 a1 a2,
 *                                            a0 = 1, transposed DF-II as scipy.signal.sosfilt),
 *                                            the chain at rest around y_d[0] (sosfilt_zi y_d[0])
 *     ref[k] = f[k] + frac (f[k-1] - f[k])   the delay's fractional part (frac = 0: f[k])
 *     v[k]   = v_rest                        for k < A (latency; v_rest = the solve of y_d[0]
 *                                            from the initial solver state)
 *     x[k]   = root of F_k(v) = ref[k - P]   for k >= A - P, on the static part (below)
 *     v[k]   = x[k]                          for k >= A without post sections (P = 0), else
 *     v[k]   = T_np[... T_1[x] ...][k]       the post sections (a filter before the hysteresis,
 *                                            a Wiener model: its approximate inverse, P = 1),
 *                                            at rest around x[A - 1]; used from k = A on
 *
 * so that v[k] = DiagnosedInverse.simulate(y_d)[k - A] for k >= A (the batch advances the post
 * sections' output by one sample: the one sample P of latency more).  The static part, with the
 * plays z_i[k-1] of the last solve (at rest at z0, normally 0):
 *
 *     Z_i(v) = clip(z_i[k-1], v - r_i, v + r_i),  h(v) = sum w_i Z_i + c,
 *     h0(v) = sum w0_i Z_i + c0
 *     F_k(v) = h(v) + sum_j g_j a_j (L_j[k-1] - h0(v))          creep (not on the first sample;
 *                                                      with lag_start, L_j[-1] = lag_start[j])
 *            - (sum_j g_j) (k = 0 ? h0(v) : L0)         lag_record = 1: the creep counted from
 *                                                      the record's start (L_j[-1] = h0[0],
 *                                                      kept in L0; pim_diagnosed.h)
 *            + q u^2 + c3 u^3,  u = (h0(v) - center) / half       asymmetry
 *            + sum_i g_i r_i (contact_i(v) ? -sign(v - Z_i) rho_k : m_i)   rate, radius family
 *            + rho_k sum_i g_i w0_i Z_i                                     rate, weight family
 *
 *            + sum_i g_i w_i (clip(zs_i[k-1], v - rs_i, v + rs_i) - Z_i)    scaled family
 *
 * (rate terms not on the first sample; the scaled family's is 0 there, its plays zs starting
 * with z).  The scaled family is exact: its radii rs_i = r_i (1 + g(s[k])) follow the rate of
 * the samples before k (pim_diagnosed.h), so no fresh rate is needed; after the solve zs_i and
 * s advance with v[k] as the model's.  rho_k = a rho_f[k-1] + (1 - a) fresh[k] with fresh
 * the rate of a nested rate-free inverse v0 run on the same ref (|v0[k] - v0[k-1]| / dt /
 * rate_scale, 0 for a jump above PIM_DIAG_STEP_SHARE input_range when rate_tau = 0), and rho_k
 * and the held terms' rate saturated as the model's (rate_saturation S > 0: rho / (1 + rho /
 * S)).  Roots:
 * between the sorted breakpoints b (z - r, z + r, v[k-1] and 10 span beyond them) F_k is a
 * polynomial (linear, cubic with the asymmetry) interpolated from interior nodes; a breakpoint
 * where |F_k - ref| <= 1e-10 (1 + |ref|) is a root too.  The root nearest the branch guess
 * wins (the first in segment order on a tie; the segments are searched outward from the guess
 * and the search stops where the rest lie farther than the root found, which chooses as a scan
 * of every segment does); out of reach, the breakpoint closest to the target.  Guess: v[k] after a jump of more
 * than 1 % of span, else 2 v[k] - v[k-1].  span = max(2 r_n, reference_range / max(|sum w|,
 * 1e-12), 1).  After the solve: plays, creep lags L_j = a_j L_j + (1 - a_j) h0 (L = h0 on the
 * first solve without lag_start), rate rho_f (from the solved input's rate, at most PIM_DINV_RATE_FEEDBACK_CAP
 * times fresh[k]) and the radius family's memory m_i of the plays in contact; with lag_record,
 * L0 = h0 of the first solve.
 *
 * State (pim_dinv_state_size doubles): [started, seen, v_rest, f_prev, s[2 ns], g[2 npost],
 * solver]
 * with solver = [started, v_prev, guess, z[n], L[m], L0[n_r]] (n_r = 1 when lag_record = 1,
 * else 0) and, with a rate effect, [rho_f, m[n],
 * v0_prev, source] where source is a rate-free solver's state (same layout, no rate), or for
 * the scaled family [s, zs[n]] (s in input unit / s).  The
 * layout is that of the Python stream's state (reference_inverse._InverseStream.labels).
 */
#ifndef PIM_DIAG_INVERSE_H
#define PIM_DIAG_INVERSE_H

#include "pim_diagnosed.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PIM_DINV_HEAD 4
#define PIM_DINV_RATE_FEEDBACK_CAP 2.0          /* reference_inverse.RATE_FEEDBACK_CAP */
#define PIM_DINV_SOLVER_MAX (3 + PIM_DINV_MAX_PLAYS + PIM_DINV_MAX_LAGS + 1 + 2 + PIM_DINV_MAX_PLAYS + \
                             3 + PIM_DINV_MAX_PLAYS + PIM_DINV_MAX_LAGS + 1)
#define PIM_DINV_STATE_MAX (PIM_DINV_HEAD + 4 * PIM_DINV_MAX_SECTIONS + PIM_DINV_SOLVER_MAX)

typedef struct {
    size_t n;              /* plays */
    const double *w;       /* weights w_i, monotone (the projection of monotone.py) */
    const double *r;       /* radii, 0 <= r_1 <= ... <= r_n */
    const double *w0;      /* reference weights w0_i (of h0) */
    double c, c0;          /* offset and reference offset */
    size_t m;              /* creep lags (0: none) */
    const double *lag_a;   /* a_j = exp(-dt / tau_j), 0 < a_j < 1 */
    const double *lag_g;   /* gains g_j */
    int asym;              /* 0: no asymmetry term */
    double q, c3, center, half;
    const double *rate_w;  /* per play the gain of its band, or NULL: no rate term */
    double dt, rate_scale, input_range;
    int rate_family;       /* PIM_DIAG_RATE_RADIUS, _WEIGHT or _SCALED */
    double rate_tau;       /* low-pass time constant of the rate [s], >= 0 */
    double rate_saturation; /* S > 0: the rate enters as rho_f / (1 + rho_f / S); 0: linear */
    double rate_growth;    /* G of the scaled family (pim_diagnosed.h) */
    double reference_range; /* >= 0: the root rule's scale (0: max(2 r_n, 1)) */
    size_t ns;             /* prefilter sections (0: none) */
    const double *sos;     /* ns rows of 6: b0 b1 b2 a0 a1 a2, a0 = 1 */
    size_t latency;        /* A, samples */
    double frac;           /* the delay's fractional part, 0 <= frac < 1 */
    size_t npost;          /* sections after the solve (a Wiener model's filter inverse; 0: none) */
    const double *post;    /* npost rows of 6, as sos */
    const double *lag_start; /* NULL: the creep lags at rest at h0[0]; else L_j[-1] =
                                lag_start[j], a common rest (pim_diagnosed.h) */
    int lag_record;        /* 0 or 1: the creep counted from each record's start, less
                              sum_j g_j h0[0] (creep_start "record" of pimodel.diagnosis.creep;
                              lag_start NULL); the solver state holds L0 */
} pim_dinv;

/* Length of the flat state (layout above). */
PIM_API size_t pim_dinv_state_size(const pim_dinv *d);

/* Length of the solver's part (without the rate source when rate = 0; the scaled family has
 * none). */
PIM_API size_t pim_dinv_solver_size(const pim_dinv *d, int rate);

/* NULL when the parameters are valid, else a static message naming the first bad one. */
PIM_API const char *pim_dinv_check(const pim_dinv *d);

/* The state before the first sample into x: all zero, the plays (of the solver and of its rate
 * source) at z0[i] (z0 NULL: 0). */
PIM_API void pim_dinv_initial_state(const pim_dinv *d, double *x, const double *z0);

/* One sample: v[k] for y_d[k]; x advances. */
PIM_API double pim_dinv_step(const pim_dinv *d, double *x, double yd);

/* N samples; x advances. */
PIM_API void pim_dinv_run(const pim_dinv *d, double *x, size_t N, const double *yd, double *v);

#ifdef __cplusplus
}
#endif

#endif /* PIM_DIAG_INVERSE_H */
