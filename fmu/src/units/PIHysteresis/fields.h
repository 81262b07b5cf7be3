/* PIHysteresis's own fields of pim_unit (inside the struct, fmi/pim_unit.h). */
double z[PIM_MAX_PLAYS] PIM_ALIGNED16; /* play states (aligned: vector loads) */
double v_safe;           /* derived: |v| <= v_safe cannot overflow a sample (model_step_safe) */
