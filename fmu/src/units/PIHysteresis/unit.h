/* The PIHysteresis unit: no code of its own beyond the framework's #if PIM_MODEL branches
 * (fmu/src/fmi/pim_unit.h: parameter check, derive, setup, sample), still to move here. */
