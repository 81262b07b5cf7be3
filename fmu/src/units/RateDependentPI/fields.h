/* RateDependentPI's own fields of pim_unit (inside the struct, fmi/pim_unit.h). */
int inverse;
double rate_gain, rate_tc, v0; /* rate gain, rate filter time constant, v[-1] */
double z[PIM_MAX_PLAYS];       /* play states */
double hist[2];                /* rate state: v[k-1], rate[k] */
double lam;                    /* the rate filter's pole exp(-Ts / rate_tc) (derived) */
