#include "core/time_average.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace cgd {

WindowAverage window_average(const std::vector<double>& t, const std::vector<double>& y, double t0, double t1,
                             int batches) {
  if (t.size() != y.size()) throw std::invalid_argument("window_average: t and y differ in length");
  if (batches < 1) throw std::invalid_argument("window_average: batches must be >= 1");
  std::vector<std::size_t> rows;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (t[i] >= t0 && t[i] < t1) rows.push_back(i);
  if (rows.size() < 2 * static_cast<std::size_t>(batches))
    throw std::invalid_argument("window [" + std::to_string(t0) + ", " + std::to_string(t1) + "] s holds " +
                                std::to_string(rows.size()) + " series rows, fewer than 2 per batch (" +
                                std::to_string(batches) + " batches)");
  std::vector<double> spacing;
  for (std::size_t k = 0; k + 1 < rows.size(); ++k) spacing.push_back(t[rows[k + 1]] - t[rows[k]]);
  std::vector<double> sorted = spacing;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];
  WindowAverage w;
  w.start_s = t[rows.front()];
  w.end_s = std::min(t1, t[rows.back()] + median);
  w.rows = rows.size();
  w.batches = batches;
  const double duration = w.end_s - w.start_s;
  std::vector<double> sum(static_cast<std::size_t>(batches), 0.0), weight(static_cast<std::size_t>(batches), 0.0);
  double total = 0, total_w = 0;
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const double dt = k + 1 < rows.size() ? spacing[k] : median;
    const double mid = t[rows[k]] + 0.5 * dt - w.start_s;
    const auto b = std::min<std::size_t>(static_cast<std::size_t>(batches) - 1,
                                         static_cast<std::size_t>(std::max(0.0, mid / duration * batches)));
    sum[b] += dt * y[rows[k]];
    weight[b] += dt;
    total += dt * y[rows[k]];
    total_w += dt;
  }
  w.mean = total / total_w;
  if (batches >= 2) {
    double mean_b = 0, var = 0;
    int used = 0;
    std::vector<double> means;
    for (int b = 0; b < batches; ++b)
      if (weight[static_cast<std::size_t>(b)] > 0) means.push_back(sum[static_cast<std::size_t>(b)] / weight[static_cast<std::size_t>(b)]);
    used = static_cast<int>(means.size());
    for (double m : means) mean_b += m / used;
    for (double m : means) var += (m - mean_b) * (m - mean_b);
    w.standard_error = used >= 2 ? std::sqrt(var / (used - 1) / used) : 0.0;
    w.batches = used;
  }
  return w;
}

}  // namespace cgd
