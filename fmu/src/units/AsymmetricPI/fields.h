/* AsymmetricPI's own fields of pim_unit (inside the struct, fmi/pim_unit.h); the order is
 * mirrored by tests/test_fmu_operators.py (AsymmetricUnit). */
double z[PIM_MAX_PLAYS]; /* play states */
int inverse, kind_in;    /* the inverse flag; the shape function phi's kind (and c_in) */
double c_in[4];
double p0, a_l, d_l, a_r, d_r; /* direct weight; ascending, descending envelopes a phi + d */
pim_asym asym;           /* derived */
