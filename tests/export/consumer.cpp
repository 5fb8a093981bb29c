// The exported header used from C++ (tests/export/export_test.sh), as a C++ force model would: the header inside a
// C++ translation unit (its functions are static inline with C linkage). Reads "phi delta_m alpha" lines on stdin,
// prints "h a H beta_bar/beta_micro". Compiled with -std=c++17 and -std=c++20, -Wall -Wextra -Werror.
#include <cstdio>
#include <iostream>

#include "model.h"

int main() {
  double phi, delta_m, alpha;
  while (std::cin >> phi >> delta_m >> alpha)
    std::printf("%.17g %.17g %.17g %.17g\n", cgd_model_master_h(phi), cgd_model_master_a(phi),
                cgd_model_H(phi, delta_m), cgd_model_correction(phi, delta_m, alpha));
  return 0;
}
