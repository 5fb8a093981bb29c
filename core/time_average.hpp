#pragma once
// Time averages of a run's series over a window, with the standard error from batch means
// (Flyvbjerg & Petersen 1989, J. Chem. Phys. 91:461; Allen & Tildesley, "Computer Simulation of
// Liquids", 2nd ed., sec. 8.4): the window [t0, t1] is cut into B batches of equal duration; the
// time-weighted mean of each batch is one sample; the standard error is sd(batch means)/sqrt(B).
// Batches must be longer than the correlation time of the signal (for the slip of a sedimenting
// suspension about one t_ref: with the default 20 t_ref window and B = 10, a batch is 2 t_ref).
// Rows are weighted by the time to the next row (the series' rows sit at uneven fluid steps).
#include <cstddef>
#include <vector>

namespace cgd {

struct WindowAverage {
  double mean = 0;
  double standard_error = 0;   // sd of the batch means / sqrt(batches); 0 when batches < 2
  int batches = 0;
  double start_s = 0, end_s = 0;
  std::size_t rows = 0;        // series rows in the window
};

/// Time-weighted mean of y(t) over [t0, t1] (rows with t0 <= t < t1, each weighted by the time to the
/// next row, the last by the median spacing) and its batch-means standard error. `t` ascending.
/// Throws std::invalid_argument if the window holds fewer than 2 * batches rows.
WindowAverage window_average(const std::vector<double>& t, const std::vector<double>& y, double t0, double t1,
                             int batches = 10);

}  // namespace cgd
