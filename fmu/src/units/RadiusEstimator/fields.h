/* RadiusEstimator's own fields of pim_unit (inside the struct, fmi/pim_unit.h): the estimator's
 * settings (gain, guard band, reversal threshold, slope check window, linear play, law PIM_LAW_DATA 0 or
 * PIM_LAW_PAPER 1), the radius estimate r_hat (output), the health bit mask of the estimate so
 * far (output, 0 before the first sample), the estimator and the health rows. */
double gain, guard, threshold;
int linear_play, slope_window, law, health;
double rhat_out[PIM_NMAX];
pim_estimator est;
pim_est_health est_health; /* rows v[k], rhat[k], y[k], e[k] of the samples processed */
