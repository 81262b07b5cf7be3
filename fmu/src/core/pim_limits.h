/*
 * pimodel C core: every fixed limit of the core and the FMU units, in one place.
 *
 * These are the only definitions: the headers of the core (pim_core.h and the others) and the
 * FMU framework include this file, and Python reads the values from the compiled core through
 * pim_limit_count / pim_limit_name / pim_limit_value (pimodel._native.LIMITS), so no limit is
 * retyped in the other language.  A new limit: define it here and add it to PIM_LIMITS.
 */
#ifndef PIM_LIMITS_H
#define PIM_LIMITS_H

/* plays and arrays */
#define PIM_MAX_PLAYS 64                       /* plays of the fixed-size users (FMU arrays) */
#define PIM_DIAG_MAX_PLAYS (2 * PIM_MAX_PLAYS) /* plays of a diagnosed model's unit (p, p_hi) */
#define PIM_DIAG_MAX_LAGS PIM_MAX_PLAYS        /* creep lags of a diagnosed model's unit */
#define PIM_DINV_MAX_PLAYS PIM_DIAG_MAX_PLAYS  /* plays of the diagnosed feedforward */
#define PIM_DINV_MAX_LAGS PIM_DIAG_MAX_LAGS    /* creep lags of the diagnosed feedforward */

/* the radius estimator (pim_estimator.h, pim_est_health.h) */
#define PIM_EST_WIN 64             /* ring buffer for the slope check (max window + 1) */
#define PIM_EST_BINS 256           /* bins of the branch slope profile (law PIM_LAW_DATA) */
#define PIM_HEALTH_CHECKPOINTS 64  /* even */
#define PIM_HEALTH_MOVING_TOL 0.01 /* drift tolerance, fraction of max(final) */
#define PIM_HEALTH_MERGE_TOL 1e-6  /* merged: gap below this fraction of max(final) */

/* the compiled loops (pim_loops.h) */
#define PIM_MAX_DYN 16 /* states of the actuator dynamics */

/* the diagnosed model (pim_diagnosed.h) and its feedforward (pim_diag_inverse.h) */
#define PIM_DIAG_MAX_DELAY 4096    /* longest delay line (samples), so d <= 4094 */
#define PIM_DIAG_MAX_ORDER 63      /* LTI order: b[0..order], a[0..order] in 64 values */
#define PIM_DIAG_MAX_ELEMENTS 8    /* further elements of the linear part (a diagnosis: <= 2) */
#define PIM_DIAG_SECTION 3         /* coefficients per section: b[0..2], a[0..2] */
#define PIM_DINV_MAX_SECTIONS 32   /* prefilter sections */
#define PIM_DINV_MAX_LATENCY 1000000 /* samples */
#define PIM_DINV_FMU_SECTIONS 10   /* DiagnosedInverse unit: sections in section[1..60] */

/* the FMU units' sampling rule (fmi/pim_unit.h) */
#define PIM_MAX_SUBSTEPS 10000000LL             /* samples per doStep */
#define PIM_MAX_SAMPLE_INDEX 4503599627370496.0 /* 2^52: k*Ts still exact in double */
#define PIM_TS_MIN 1e-12                        /* smallest sample time [s] */
#define PIM_SAMPLE_TOL 1e-9                     /* tolerance of the sampling rule, in samples */

/* The exported table: X(name, is_integer) per limit. */
#define PIM_LIMITS(X)                                                                           \
    X(PIM_MAX_PLAYS, 1) X(PIM_DIAG_MAX_PLAYS, 1) X(PIM_DIAG_MAX_LAGS, 1)                        \
    X(PIM_DINV_MAX_PLAYS, 1) X(PIM_DINV_MAX_LAGS, 1) X(PIM_EST_WIN, 1) X(PIM_EST_BINS, 1)       \
    X(PIM_HEALTH_CHECKPOINTS, 1) X(PIM_HEALTH_MOVING_TOL, 0) X(PIM_HEALTH_MERGE_TOL, 0)         \
    X(PIM_MAX_DYN, 1) X(PIM_DIAG_MAX_DELAY, 1) X(PIM_DIAG_MAX_ORDER, 1)                         \
    X(PIM_DIAG_MAX_ELEMENTS, 1) X(PIM_DIAG_SECTION, 1) X(PIM_DINV_MAX_SECTIONS, 1)              \
    X(PIM_DINV_MAX_LATENCY, 1) X(PIM_DINV_FMU_SECTIONS, 1) X(PIM_MAX_SUBSTEPS, 1)              \
    X(PIM_MAX_SAMPLE_INDEX, 1) X(PIM_TS_MIN, 0) X(PIM_SAMPLE_TOL, 0)

/* Codes of the core's enumerations and constants of its algorithms, defined in their own
 * headers (pim_estimator.h, pim_generalized.h, pim_diag_inverse.h) and exported beside the limits so that Python never retypes them. */
#define PIM_CODES(X)                                                                            \
    X(PIM_LAW_DATA, 1) X(PIM_LAW_PAPER, 1) X(PIM_ENV_POLY2, 1) X(PIM_ENV_TANH, 1)             \
    X(PIM_ENV_POLY2_INV, 1) X(PIM_ENV_TANH_INV, 1) X(PIM_DINV_RATE_FEEDBACK_CAP, 0)

#endif /* PIM_LIMITS_H */
