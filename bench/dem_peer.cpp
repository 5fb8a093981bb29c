// cgd-bench-dem: the DEM peer benchmark (../shared/peers/README.md) run by cgd's engine from the
// same LAMMPS data file (same particles, positions, velocities), the same contact law and
// parameters (data/scenes/bench_<case>.toml), warm-up steps then timed steps. Prints one line in
// the format of peers/bench.sh, plus where the time went. Never asserted anywhere: figures only.
//   cgd-bench-dem --data /tmp/cgd-peers/data/l10.data [--scene S.toml] [--neq 200] [--steps 2000]
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "core/mpi_init.hpp"
#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/scene.hpp"
#include "core/timers.hpp"
#include "sim/run.hpp"

namespace {

struct DataFile {
  std::int64_t n = 0;
  std::array<double, 3> box{};
  std::vector<std::int64_t> id;
  std::vector<double> diameter, x, v, w;
};

DataFile read_lammps_data(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw cgd::InputError(path + ": cannot open the LAMMPS data file");
  DataFile d;
  std::string line;
  std::vector<std::int64_t> index;  // id -> row
  while (std::getline(in, line)) {
    if (line.find(" atoms") != std::string::npos) d.n = std::stoll(line);
    for (int k = 0; k < 3; ++k) {
      const char* tag[3] = {"xlo xhi", "ylo yhi", "zlo zhi"};
      if (line.find(tag[k]) != std::string::npos) {
        std::istringstream s(line);
        double lo, hi;
        s >> lo >> hi;
        d.box[k] = hi - lo;
      }
    }
    if (line.rfind("Atoms", 0) == 0) {
      std::getline(in, line);
      d.id.resize(d.n);
      d.diameter.resize(d.n);
      d.x.resize(3 * d.n);
      index.assign(d.n + 1, -1);
      for (std::int64_t i = 0; i < d.n; ++i) {
        std::getline(in, line);
        std::istringstream s(line);
        std::int64_t id, type;
        double dens;
        s >> id >> type >> d.diameter[i] >> dens >> d.x[3 * i] >> d.x[3 * i + 1] >> d.x[3 * i + 2];
        d.id[i] = id;
        index[id] = i;
      }
    }
    if (line.rfind("Velocities", 0) == 0) {
      std::getline(in, line);
      d.v.resize(3 * d.n);
      d.w.resize(3 * d.n);
      for (std::int64_t k = 0; k < d.n; ++k) {
        std::getline(in, line);
        std::istringstream s(line);
        std::int64_t id;
        s >> id;
        const std::int64_t i = index[id];
        s >> d.v[3 * i] >> d.v[3 * i + 1] >> d.v[3 * i + 2] >> d.w[3 * i] >> d.w[3 * i + 1] >> d.w[3 * i + 2];
      }
    }
  }
  if (d.id.empty() || d.v.empty()) throw cgd::InputError(path + ": no Atoms/Velocities section");
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  const int status = cgd::run_tool([&] {
    CLI::App app{"DEM peer benchmark: cgd's engine on a LAMMPS data file"};
    std::string data, scene_path;
    long neq = 200, steps = 2000;
    app.add_option("--data", data, "LAMMPS data file from ../shared/peers/make_data.sh")->required();
    app.add_option("--scene", scene_path, "scene with the physics (default data/scenes/bench_<case>.toml)");
    app.add_option("--neq", neq, "warm-up steps");
    app.add_option("--steps", steps, "timed steps");
    cgd::parse_command_line(app, argc, argv, "cgd-bench-dem");
    const std::string case_name = std::filesystem::path(data).stem().string();
    if (scene_path.empty()) scene_path = std::string(CGD_SOURCE_DIR) + "/data/scenes/bench_" + case_name + ".toml";
    DataFile d = read_lammps_data(data);
    cgd::Scene scene = cgd::load_scene(scene_path);
    scene.domain.size_m = d.box;
    cgd::dem::DemSettings settings = cgd::dem_settings_from_scene(scene);
    settings.diameter_m = d.diameter[0];
    cgd::dem::DemSystem sys(settings, MPI_COMM_WORLD);
    int rank = 0, ranks = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    std::vector<std::int64_t> ids;
    std::vector<double> x, v, w;
    for (std::int64_t i = 0; i < d.n; ++i) {
      double q[3] = {d.x[3 * i], d.x[3 * i + 1], d.x[3 * i + 2]};
      sys.slabs().wrap(q);
      if (sys.slabs().owner(q[1]) != rank) continue;
      ids.push_back(d.id[i]);
      x.insert(x.end(), q, q + 3);
      v.insert(v.end(), &d.v[3 * i], &d.v[3 * i + 3]);
      w.insert(w.end(), &d.w[3 * i], &d.w[3 * i + 3]);
    }
    const std::int64_t n_total = d.n;
    d = DataFile{};  // the file's copy is not needed any more: peak memory is the engine's
    sys.set_particles(std::move(ids), std::move(x), std::move(v), settings.friction ? std::move(w) : std::vector<double>{});
    for (long s = 0; s < neq; ++s) sys.step();
    const std::vector<double> before = sys.timers().all_seconds();
    const std::int64_t rebuilds_before = sys.rebuilds();
    MPI_Barrier(MPI_COMM_WORLD);
    const double t0 = cgd::wall_seconds();
    for (long s = 0; s < steps; ++s) sys.step();
    MPI_Barrier(MPI_COMM_WORLD);
    const double loop = cgd::wall_seconds() - t0;
    double bytes = static_cast<double>(sys.bytes());
    MPI_Allreduce(MPI_IN_PLACE, &bytes, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    std::vector<double> phases = sys.timers().all_seconds();
    for (std::size_t k = 0; k < phases.size(); ++k) phases[k] -= before[k];
    MPI_Allreduce(MPI_IN_PLACE, phases.data(), static_cast<int>(phases.size()), MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    double entries = static_cast<double>(sys.neighbor_entries()), ghosts = static_cast<double>(sys.ghosts());
    MPI_Allreduce(MPI_IN_PLACE, &entries, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    MPI_Allreduce(MPI_IN_PLACE, &ghosts, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    if (rank == 0) {
      std::printf("cgd %s N=%lld ranks=%d loop_s=%.3f ps_per_s_per_core=%.3e bytes_per_particle=%.0f\n",
                  case_name.c_str(), static_cast<long long>(n_total), ranks, loop,
                  static_cast<double>(n_total) * static_cast<double>(steps) / loop / ranks, bytes / static_cast<double>(n_total));
      std::printf("# phases (s, slowest rank):");
      for (std::size_t k = 0; k < phases.size(); ++k)
        std::printf(" %s=%.3f", sys.timers().names()[k].c_str(), phases[k]);
      std::printf("; rebuilds=%lld; list entries/particle=%.2f; ghosts/particle=%.3f\n",
                  static_cast<long long>(sys.rebuilds() - rebuilds_before), entries / static_cast<double>(n_total),
                  ghosts / static_cast<double>(n_total));
    }
    return cgd::kExitOk;
  });
  MPI_Finalize();
  return status;
}
