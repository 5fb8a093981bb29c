/* The exported header used from C99 (tests/export/export_test.sh): reads "phi delta_m alpha" lines on stdin and
 * prints "h a H beta_bar/beta_micro" per line. Compiled with -std=c99 -pedantic -Wall -Wextra -Werror against the
 * header of the model named "model" (cgd-export ... --name model). */
#include <stdio.h>

#include "model.h"

int main(void) {
  double phi, delta_m, alpha;
  while (scanf("%lf %lf %lf", &phi, &delta_m, &alpha) == 3)
    printf("%.17g %.17g %.17g %.17g\n", cgd_model_master_h(phi), cgd_model_master_a(phi), cgd_model_H(phi, delta_m),
           cgd_model_correction(phi, delta_m, alpha));
  return 0;
}
