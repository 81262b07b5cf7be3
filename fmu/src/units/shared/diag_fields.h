/* The static part's fields of pim_unit shared by DiagnosedModel and DiagnosedInverse (included
 * inside the struct by their fields.h; pim_diagnosed.h): signed weights w of plays 1..64 in p,
 * radii in r, plays 65..128 in p_hi, r_hi, w0_hi, rate_band_gain_hi; the plays' arrays joined
 * (derived, unit_diag_join) and the creep poles exp(-Ts / creep_tau) derived into a. */
#define PIM_UNIT_NMAX PIM_DIAG_MAX_PLAYS /* plays 1..64 in p, r, ...; 65..128 in p_hi, r_hi, ... */
double w0[PIM_NMAX], creep_gain[PIM_NMAX], creep_tau[PIM_NMAX], rate_band_gain[PIM_NMAX];
double p_hi[PIM_NMAX], r_hi[PIM_NMAX], w0_hi[PIM_NMAX], rate_band_gain_hi[PIM_NMAX];
double offset, reference_offset, asym_q, asym_c3, center, half_range, rate_scale, input_range;
int n_lags, rate_family, creep_start;
double creep_start_level[PIM_NMAX]; /* the creep lags' common rest (creep_start = 1) */
double rate_tau, rate_saturation, rate_growth;
/* derived */
double dw[PIM_DIAG_MAX_PLAYS], dr[PIM_DIAG_MAX_PLAYS], dw0[PIM_DIAG_MAX_PLAYS],
    drb[PIM_DIAG_MAX_PLAYS];
double a[PIM_NMAX];
