/* InversePI's own fields of pim_unit (inside the struct, fmi/pim_unit.h). */
int adaptive;                                 /* Boolean: radii from the input r_hat */
double rhat_in[PIM_NMAX];                     /* input r_hat (adaptive) */
double z[PIM_MAX_PLAYS];                      /* play states (of the inverse) */
double pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS]; /* the inverse's plays (derived) */
