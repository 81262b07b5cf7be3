/*
 * Health of a radius estimate, accumulated sample by sample in bounded memory (the
 * RadiusEstimator FMU) and evaluated on the estimate history rhat[0..N-1] (the Python
 * pimodel.estimator_health calls the same code on its history), so that the checks have one
 * definition.
 *
 * Per row k the caller adds the input v[k] [input unit] and the estimate rhat[k] used at
 * sample k (before its update).  The checks, on the last row rhat[N-1] ("final"):
 *   PIM_HEALTH_EXCITATION  the record cannot excite every play (Lemma 2, Prop. 2): input range
 *                          A = max v - min v is 0, or no reversal was seen, or A <= the loop
 *                          width rho = 2 sum p_j r_j / sum p_j, or A <= 2 r_n (r = final);
 *   PIM_HEALTH_MERGED      adjacent plays merged: final[j+1] - final[j] <= 1e-6 max(final);
 *   PIM_HEALTH_PINNED      a radius at the projection bound: final[j] == 0 (j >= 2 with a
 *                          declared linear play);
 *   PIM_HEALTH_MOVING      still moving: max_j |mean over Q4 - mean over Q3| > 1 % max(final),
 *                          Q4 the last quarter of the rows and Q3 the quarter before;
 *   PIM_HEALTH_FIT         (only when the accumulator tracks the fit, with_fit) the model does
 *                          not fit: the RMS of e[k] = yhat[k] - y[k] over Q4 exceeds
 *                          1.1 sigma_y + 1e-4 (max y - min y), with the noise level
 *                          sigma_y = sqrt(pi / 2) mean|y[k] - 2 y[k-1] + y[k-2]| / sqrt(6)
 *                          (N >= 3; the mean absolute second difference, a streaming stand-in
 *                          for the median that pimodel.estimator_settings.noise_level uses).
 * The quarters: q = N / 4 (integer division), Q3 = rows [a, b), Q4 = rows [b, N) with
 * a = N - 2q, b = N - q rounded down to the checkpoint grid.  Cumulative sums of the rows are
 * kept every `block` rows (block = 1 while N <= PIM_HEALTH_CHECKPOINTS, then doubled whenever
 * the checkpoints are full), so the boundaries are exact for N <= 64 and within N / 32 rows
 * of N - 2q and N - q beyond.  No check when q < 1.
 * The struct is plain data (copyable FMU state); every field is a double except n.
 */
#ifndef PIM_EST_HEALTH_H
#define PIM_EST_HEALTH_H

#include "pim_core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PIM_HEALTH_EXCITATION 1
#define PIM_HEALTH_MERGED 2
#define PIM_HEALTH_PINNED 4
#define PIM_HEALTH_MOVING 8
#define PIM_HEALTH_FIT 16

typedef struct {
    size_t n;
    int with_fit;  /* y[k] and e[k] are added too (PIM_HEALTH_FIT) */
    double count;  /* rows added */
    double block;  /* rows per checkpoint, a power of 2 */
    double next;   /* row count at which the next checkpoint is due */
    double ncheck; /* checkpoints held: sums of the first i * block rows, i = 1..ncheck */
    double vmin, vmax; /* input range seen */
    double last[PIM_MAX_PLAYS]; /* the last row (final) */
    double sum[PIM_MAX_PLAYS];  /* sum of all rows */
    double check[PIM_HEALTH_CHECKPOINTS][PIM_MAX_PLAYS];
    /* fit (with_fit): sum of e^2 (and at the checkpoints), output range, the last two outputs
     * and the sum of |second differences| of y */
    double esq, check_esq[PIM_HEALTH_CHECKPOINTS];
    double ymin, ymax, y1, y2, d2sum;
} pim_est_health;

/* Empty accumulator for n plays (1 <= n <= PIM_MAX_PLAYS), tracking the fit when with_fit;
 * returns NULL or a message. */
PIM_API const char *pim_health_init(pim_est_health *h, size_t n, int with_fit);

/* Adds N rows: inputs v[0..N-1] (nullable: the input range is then not tracked and stays 0,
 * for a caller that checks the excitation itself), estimates R (N x n, row by row) and, when
 * the accumulator tracks the fit, the measured outputs y and the model errors e (else NULL). */
PIM_API void pim_health_add(pim_est_health *h, size_t N, const double *v, const double *R,
                            const double *y, const double *e);

/*
 * The checks on the rows added so far, with weights p (> 0), `linear_play` (rhat_1 = 0 held on
 * purpose, not reported as pinned) and `reversals` (input reversals the caller counted).
 * Returns the bit mask of the failed checks; writes the drift max_j |mean Q4 - mean Q3|
 * [input unit] (0 when not checked), the input range, the fit RMS over Q4 and its bound
 * (0 when not checked) into fit[0], fit[1] (nullable), and, when not NULL, merged[j] = 1 if
 * plays j and j + 1 (0-based) merged (n - 1 entries) and pinned[j] = 1 if play j is pinned.
 */
PIM_API int pim_health_eval(const pim_est_health *h, const double *p, int linear_play,
                            long reversals, double *drift, double *input_range, double *fit,
                            int *merged, int *pinned);

/* NULL if h is an admissible state for n plays (restored FMU state), else a message. */
PIM_API const char *pim_health_check(const pim_est_health *h, size_t n);

PIM_API size_t pim_health_sizeof(void);

#ifdef __cplusplus
}
#endif

#endif /* PIM_EST_HEALTH_H */
