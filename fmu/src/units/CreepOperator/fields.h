/* CreepOperator's own fields of pim_unit (inside the struct, fmi/pim_unit.h); the gains c are
 * stored in p and the time constants tau in r. */
int inverse;
double z[PIM_MAX_PLAYS]; /* the lags' states */
double a[PIM_NMAX];      /* the lags' poles exp(-Ts / tau) (derived) */
