/* The one C file that gives the exported functions external C linkage, for Fortran (bind(C)) callers. */
#define CGD_MODEL_IMPLEMENTATION
#include "model.h"
