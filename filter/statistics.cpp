#include "filter/statistics.hpp"

#include <algorithm>
#include <cmath>

namespace cgd::filter {

double integrated_autocorrelation_time(const std::vector<double>& series, double window_factor) {
  const std::size_t n = series.size();
  if (n < 4) return 0.5;
  double mean = 0;
  for (double x : series) mean += x;
  mean /= static_cast<double>(n);
  auto autocov = [&](std::size_t lag) {
    double s = 0;
    for (std::size_t t = 0; t + lag < n; ++t) s += (series[t] - mean) * (series[t + lag] - mean);
    return s / static_cast<double>(n);
  };
  const double c0 = autocov(0);
  if (!(c0 > 0)) return 0.5;
  double tau = 0.5;
  for (std::size_t lag = 1; lag < n; ++lag) {
    tau += autocov(lag) / c0;
    if (static_cast<double>(lag) >= window_factor * tau) break;
  }
  return std::max(tau, 0.5);
}

std::int64_t block_length(double tau, std::int64_t n) {
  std::int64_t b = std::max<std::int64_t>(1, std::llround(2.0 * tau));
  return std::max<std::int64_t>(1, std::min(b, n / 2));
}

double percentile(std::vector<double>& values, double q) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const double pos = q * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (pos - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

}  // namespace cgd::filter
