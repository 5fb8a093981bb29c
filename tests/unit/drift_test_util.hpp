#pragma once
// A drift table model file (curves = "drift_table", docs/schema-drag-model.md "/drift_table") for the tests of
// the drift-velocity law (tests/unit/test_drift.cpp, tests/mpi/test_coupled_mpi.cpp), written through the
// schema's own writer for the scene's particle/fluid system, as cgd-fit --drift-table writes one.
#include <cstdint>
#include <string>
#include <vector>

#include "core/physical_system.hpp"
#include "core/scene.hpp"
#include "core/schema/drag_model.hpp"

namespace cgd::testing {

/// Writes `path`: H on the bin centres `phi` (at least 2) x `slip` (u_t), row-major; the system of `scene` (loaded
/// with a micro law, whose law becomes the table's micro_drag). Counts and sums zero, every bin "measured".
inline void write_drift_model(const std::string& path, const Scene& scene, const std::vector<double>& phi,
                              const std::vector<double>& slip, const std::vector<double>& H,
                              std::int64_t cells_across = 4) {
  schema::DragModelFile m;
  m.system = physical_system(scene);
  m.model_form = "drift-velocity closure (test table)";
  m.calibration_operator = CalibrationOperator::Grid;
  m.curves = schema::ModelCurves::DriftTable;
  m.table_cells_across = cells_across;
  m.phi_crit = phi.front() > 0 ? phi.front() : 0.016;  // the reader wants (0, 1); not used by the drift law
  m.phi_max = phi.back();
  m.h_max = 0.99;
  schema::SplineRecord h;
  h.order = 2;
  h.knots.push_back(phi.front());
  h.knots.insert(h.knots.end(), phi.begin(), phi.end());
  h.knots.push_back(phi.back());
  h.coefficients.assign(phi.size(), 0.0);
  h.meaning = "the rows' phi-only H_grid (zero here)";
  m.h = h;
  m.log_a = h;
  m.log_a.coefficients.assign(phi.size(), -700.0);
  m.log_a.meaning = "a = 0";
  m.c_corr.a = 1.0, m.c_corr.k = 0.0, m.c_corr.source = "none";
  schema::DragModelFile::DriftTable t;
  t.phi = phi;
  t.slip = slip;
  t.H = H;
  const std::size_t n = phi.size() * slip.size();
  t.numerator.assign(n, 0.0), t.denominator.assign(n, 0.0), t.magnitude.assign(n, 0.0);
  t.count.assign(n, 0), t.filled.assign(n, 0);
  t.phi_only_H.assign(phi.size(), 0.0);
  t.source_group = "/grids/" + std::to_string(cells_across) + "/drift";
  t.fill_rule = "test table";
  t.min_count = 0;
  t.min_alignment = 0.25;
  t.phi_bin_width = phi.size() > 1 ? phi[1] - phi[0] : 0.01;
  t.slip_bin_width = slip.size() > 1 ? slip[1] - slip[0] : 0.1;
  m.drift_table = t;
  schema::write_drag_model(path, scene, m);
}

}  // namespace cgd::testing
