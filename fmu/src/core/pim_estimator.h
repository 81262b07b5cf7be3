/*
 * Adaptive estimation of PI play radii (Al Janaideh & Tan), robust discrete-time form.
 *
 * Per sample k, with input v[k] [input unit] and measured output y[k] [output unit]:
 *   1. model:  zhat_j[k] = clamp(zhat_j[k-1], v[k] - rhat_j[k], v[k] + rhat_j[k]),
 *              yhat[k] = sum_j p_j zhat_j[k],  e[k] = yhat[k] - y[k]            (paper eqs. 7-8)
 *   2. segment bookkeeping: direction s (+1/-1) of the current monotone segment, its start
 *      v_rev (the last reversal, an input extreme), and per play whether it was surely on its
 *      envelope at that reversal: sat_j = 1 iff the segment that ended there travelled at least
 *      2 rhat_j + guard (a travel of 2 r_j saturates a play from any state; the test uses no
 *      measured output, so which samples are used does not depend on the noise).  A reversal is
 *      declared once v has moved back from the running extreme by more than the threshold h;
 *      samples within h of the extreme are not used.  Holds (v[k] == v[k-1]) keep s and are
 *      used.
 *   3. principal case at the input travel d = |v[k] - v_rev|: which plays are on their envelope.
 *      law PIM_LAW_DATA (default): from the measured branches.  For d <= t_prev (travel of
 *      the segment before the reversal) the branch increment is s (y - y_rev) =
 *      sum_j p_j max(0, d - 2 r_j) for any history (Madelung), slopes P_i = p_1 + .. + p_i.
 *      The increments s (y[k] - y[k-1]) are pooled in PIM_EST_BINS travel bins (width set at
 *      the first reversal to 2.2 t_prev / PIM_EST_BINS, doubled by merging pairs as the travel
 *      grows); at each reversal, and whenever the profile reaches a new bin, the
 *      non-decreasing count of saturated plays per bin minimising sum_b C_b (S_b/C_b - P_i)^2
 *      is fitted (dynamic programme) and gives breakpoints edge_j.  Play j is on iff
 *      d >= edge_j; within g = max(guard, bin width) of edge_j the estimate decides
 *      (d >= 2 rhat_j) if |2 rhat_j - edge_j| < g and |d - 2 rhat_j| >= guard, else the sample
 *      is skipped; an interior play needs edge_j + g <= t_prev (saturated at the reversal);
 *      beyond the profiled travel only the all-on case is used; while the profile does not
 *      cover t_prev, a play not yet profiled follows the paper's rule below.
 *      law PIM_LAW_PAPER: from the estimate, play j on its envelope iff
 *      d >= 2 rhat_j[k] (no noisy slope is differenced).  The sample is used only when every
 *      interior play was saturated at the reversal (else its state is unknown: minor loops),
 *      and only when d is at least `guard` away from every breakpoint 2 rhat_j (a sample near a
 *      breakpoint may be misclassified, which biases the estimate under noise).
 *      Slope check (slope_window m > 0, paper law only): the measured output change over the
 *      m samples before k (within the segment; y[k] itself is not used, so the choice does not
 *      correlate with the current noise) must match the case model's change within slope_tol * min p_j per
 *      unit of travel; otherwise the regime read from rhat is wrong (an overestimated radius
 *      whose true play is already on its envelope) and the sample is skipped.  Without this
 *      check a radius overestimate can run away.
 *      Case model   ybar = sum_{on} p_j (v - s rhat_j) + sum_{interior} p_j (v_rev + s rhat_j),
 *      modified error e_delta = ybar - y = s phi^T (r - rhat),  phi_j = +p_j (on), -p_j (interior)
 *   4. gradient law with projection:
 *      rhat[k+1] = Proj( rhat[k] + dt * g_j(t) * e_delta * s * phi_j ),
 *      g_j(t) = gain_j / (1 + t / anneal_time)   (anneal_time <= 0: constant gain),
 *      each step component clipped to +-max_step (max_step <= 0: no clip), Proj the weighted
 *      Euclidean projection (weights 1/gain_j) onto 0 <= rhat_1 <= ... <= rhat_n (pool adjacent
 *      violators, then clip at 0); with known_linear, rhat_1 = 0 is held fixed.
 * No memory is allocated; the struct is plain data, copyable for FMU state get/set.
 */
#ifndef PIM_ESTIMATOR_H
#define PIM_ESTIMATOR_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PIM_LAW_DATA 0    /* regime from the measured branch profile (default) */
#define PIM_LAW_PAPER 1   /* regime from the estimate, as in the paper */

typedef struct {
    /* parameters */
    size_t n;
    double p[PIM_MAX_PLAYS];
    double gain[PIM_MAX_PLAYS];
    double dt;
    double threshold;   /* reversal threshold h [input unit] */
    double max_step;    /* per-sample clip of the radius update [input unit], <= 0: none */
    double anneal_time; /* gain annealing time constant [s], <= 0: constant gains */
    double guard;       /* samples with |d - 2 rhat_j| < guard for some j are not used */
    int known_linear;   /* rhat_1 fixed at 0 */
    int slope_window;   /* samples of the slope check window (0: no check) */
    double slope_tol;   /* tolerated slope mismatch, in units of the smallest weight */
    int law;            /* PIM_LAW_DATA or PIM_LAW_PAPER */
    /* state (see pim_est_get_state for the flat layout) */
    double rhat[PIM_MAX_PLAYS];
    double zhat[PIM_MAX_PLAYS];
    double sat[PIM_MAX_PLAYS];     /* 1 if play j was saturated at the last reversal */
    double v_first;  /* first input sample */
    double v_start;  /* start of the current segment (last reversal, or the first sample) */
    double v_ext;    /* running extreme of the current segment */
    double v_rev;    /* input at the last reversal */
    double dir;      /* segment direction +1/-1, 0 before the first move */
    double have_rev; /* 1 once a reversal has been seen */
    double started;  /* 1 once a sample has been processed */
    double time;     /* elapsed time k*dt [s] */
    double nseg;     /* samples seen since the last reversal */
    double head;     /* ring buffer position */
    double vbuf[PIM_EST_WIN], ybuf[PIM_EST_WIN]; /* last inputs and outputs */
    /* branch profile (law PIM_LAW_DATA) */
    double t_prev;   /* input travel of the segment that ended at the last reversal */
    double y_ext;    /* output at the running extreme v_ext */
    double x_last;   /* travel of the last profiled point of the current branch */
    double y_last;   /* output there */
    double width;    /* bin width [input unit], 0 until the first reversal */
    double top;      /* highest bin with data, -1 if none */
    double fitted;   /* 1 once the regime table has been fitted */
    double edge[PIM_MAX_PLAYS];  /* fitted breakpoints: travel where play j joins (inf: never) */
    double S[PIM_EST_BINS];      /* sum of s * (output change) per travel bin */
    double C[PIM_EST_BINS];      /* sum of travel per bin */
} pim_estimator;

/* Flat state length: 4n + 17 + 2 PIM_EST_WIN + 2 PIM_EST_BINS doubles. */
#define PIM_EST_STATE_SIZE(n) (4 * (n) + 17 + 2 * PIM_EST_WIN + 2 * PIM_EST_BINS)

/*
 * Initialise: n plays with weights p (> 0), gains (>= 0), initial radii rhat0 (projected onto
 * the ordered set), sample time dt > 0, model initial play state z0 (same for all plays),
 * reversal threshold >= 0, max_step, anneal_time, guard >= 0 (see the struct).
 * Returns NULL on success or a static message naming the bad parameter.
 */
PIM_API const char *pim_est_init(pim_estimator *est, size_t n, const double *p,
                                 const double *gains, const double *rhat0, double dt, double z0,
                                 double threshold, double max_step, double anneal_time,
                                 double guard, int known_linear);

/*
 * One sample.  Writes the radii used at step k (rhat[k], before the update) to rhat_used
 * (nullable), and yhat[k], e[k], e_delta[k] (0 when unused); returns 1 if the sample was used
 * for adaptation, 0 if not, -1 if v or y is not finite (state unchanged).
 */
PIM_API int pim_est_step(pim_estimator *est, double v, double y, double *rhat_used,
                         double *yhat, double *e, double *e_delta);

/* Batch: N samples; R (N*n, nullable) gets rhat[k] row by row; used (nullable) the flags.
 * Returns the index of the first non-finite sample, or -1 if all were processed. */
PIM_API long pim_est_run(pim_estimator *est, size_t N, const double *v, const double *y,
                         double *R, double *yhat, double *e, double *e_delta, double *used);

PIM_API size_t pim_est_sizeof(void);
PIM_API void pim_est_get_state(const pim_estimator *est, double *state);
/* Slope check settings (see above); window 0 disables it, at most PIM_EST_WIN - 1.  Returns
 * NULL or a message.  pim_est_init sets window 8, tolerance 0.5. */
PIM_API const char *pim_est_set_slope_check(pim_estimator *est, int window, double tol);

/* Law: PIM_LAW_DATA (set by pim_est_init) or PIM_LAW_PAPER.  Returns NULL or a message. */
PIM_API const char *pim_est_set_law(pim_estimator *est, int law);

/* Returns NULL or a message if the state is not admissible (non-finite, unordered radii). */
PIM_API const char *pim_est_set_state(pim_estimator *est, const double *state);

/* Weighted projection onto 0 <= x_1 <= ... <= x_n (weights w > 0), in place; x_1 held at 0
 * when fix_first.  Exposed for tests. */
PIM_API void pim_project_ordered(size_t n, double *x, const double *w, int fix_first);

#ifdef __cplusplus
}
#endif

#endif /* PIM_ESTIMATOR_H */
