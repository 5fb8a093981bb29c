#pragma once
// Statistics of the filter's per-snapshot sums: autocorrelation time, blocks, block bootstrap.
#include <cstdint>
#include <vector>

namespace cgd::filter {

/// Integrated autocorrelation time of a series, in samples, with Sokal's automatic window
/// (Sokal 1997, "Monte Carlo methods in statistical mechanics", sec. 3): tau = 1/2 + sum_{t=1}^{W} rho(t),
/// W the smallest lag with W >= c tau (c = 5). 1/2 for uncorrelated samples; at least 1/2; a constant
/// or too short series (fewer than 4 samples) gives 1/2.
double integrated_autocorrelation_time(const std::vector<double>& series, double window_factor = 5.0);

/// Block length for the block bootstrap of a series with autocorrelation time tau (samples):
/// max(1, round(2 tau)), the spacing at which samples are roughly independent, capped at n/2 so that
/// at least two blocks exist.
std::int64_t block_length(double tau, std::int64_t n);

/// Percentile (type 7, linear between order statistics) of `values` (sorted in place), q in [0, 1].
double percentile(std::vector<double>& values, double q);

}  // namespace cgd::filter
