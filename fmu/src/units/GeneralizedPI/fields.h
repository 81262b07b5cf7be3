/* GeneralizedPI's own fields of pim_unit (inside the struct, fmi/pim_unit.h): the inverse flag,
 * the input envelope h (kind_in, c_in) and output envelope g (kind_out, c_out),
 * pim_generalized.h. */
int inverse, kind_in, kind_out;
double c_in[4], c_out[4];
double z[PIM_MAX_PLAYS];                      /* play states */
double pinv[PIM_MAX_PLAYS], rinv[PIM_MAX_PLAYS]; /* the inverse's plays (derived, inverse) */
