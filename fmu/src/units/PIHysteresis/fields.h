/* PIHysteresis's own fields of pim_unit (inside the struct, fmi/pim_unit.h). */
double z[PIM_MAX_PLAYS]; /* play states */
