// cgd-export: a drag model -> a C header, a Fortran module and CSV tables for other codes (docs/export.md;
// fit/export_model.hpp). A thin driver: parse, read and check every input, build every file in memory, then write
// them (temporary names, renamed when all are written), so bad input leaves nothing behind.
#include <mpi.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "core/mpi_init.hpp"
#include "core/cli.hpp"
#include "core/error.hpp"
#include "core/filtered_drag.hpp"
#include "core/scene.hpp"
#include "core/text_file.hpp"
#include "fit/export_model.hpp"

namespace fs = std::filesystem;

namespace {

/// What the header's comment says about where the model came from, beyond the in-memory model: the file's
/// code_version and created, its /provenance text and its /sources (the filtered files and their checksums).
/// The lines of the header's provenance: who wrote the model, the grids and filtered files it was fitted on.
std::vector<std::string> model_provenance(const cgd::DragModel& m) {
  std::vector<std::string> out;
  std::string made = "written by cgd";
  if (!m.code_version.empty()) made += " " + m.code_version;
  if (!m.created.empty()) made += " on " + m.created;
  out.push_back(made);
  if (!m.calibrated_cells_across.empty()) {
    std::string grids = "calibrated grids:";
    for (std::int64_t n : m.calibrated_cells_across) grids += " " + std::to_string(n);
    out.push_back(grids + " cells across");
  }
  for (std::size_t i = 0; i < m.source_files.size(); ++i)
    out.push_back("filtered file: " + m.source_files[i] +
                  (i < m.source_checksums.size() ? " (checksum " + m.source_checksums[i] + ")" : ""));
  for (const auto& [key, text] : m.provenance) out.push_back(key + ": " + text);
  return out;
}

std::string default_name(const std::string& stem) {
  std::string s;
  for (char c : stem) s += std::isalnum(static_cast<unsigned char>(c)) ? static_cast<char>(std::tolower(c)) : '_';
  if (s.empty() || !std::isalpha(static_cast<unsigned char>(s[0]))) s = "m_" + s;
  return s;
}

void check_name(const std::string& name) {
  bool ok = !name.empty() && name.size() <= 40 && std::isalpha(static_cast<unsigned char>(name[0]));
  for (char c : name) ok = ok && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (!ok)
    throw cgd::InputError("cgd-export: --name " + name +
                          ": allowed a C and Fortran identifier part: a letter, then letters, digits or _, at most 40");
}

}  // namespace

int main(int argc, char** argv) {
  cgd::init_mpi(&argc, &argv);
  const int status = cgd::run_tool([&] {
    std::string model_path, scene_path, output, name;
    std::vector<std::string> overrides;
    std::vector<double> csv_deltas_dp;
    bool radl = false, force = false, quiet = false;
    double l_char_m = 0;
    CLI::App app{
        "Export a filtered drag model for other codes: NAME.h (a C99 header: h, a, H(phi, Delta) and "
        "beta_bar/beta_micro with the engine's clamps), NAME.f90 (Fortran bind(C) interfaces), NAME_pieces.csv (the "
        "curves as piecewise cubics c0 + c1 x + c2 x^2 + c3 x^3 per interval) and NAME_H.csv (H over phi x Delta "
        "with the bands) in DIR (docs/export.md)",
        "cgd-export"};
    app.footer(
        "Examples:\n"
        "  cgd-export data/models/half_box.h5 -o out/export             # out/export/half_box.{h,f90,_pieces.csv,_H.csv}\n"
        "  cgd-export out/fit/perfect_c4.h5 --name perfect4 -o out/export  # a --grid-table model\n"
        "  cgd-export --radl2014 --scene data/scenes/table1_phi005.toml -o out/export   # Radl 2014 at the scene's L_char\n"
        "  cgd-export --radl2014 --l-char-m 3.0135e-4 -o out/export");
    app.add_option("model", model_path, "Model file of cgd-fit (splines, or a --grid-table table)")
        ->type_name("MODEL.h5");
    app.add_flag("--radl2014", radl, "Export the published Radl & Sundaresan (2014) curves instead of a model file");
    app.add_option("--scene", scene_path, "With --radl2014: the scene whose L_char (and d_p) to use")
        ->type_name("SCENE.toml");
    app.add_option("--set", overrides, "With --scene: override a scene key")->type_name("KEY=VALUE");
    app.add_option("--l-char-m", l_char_m, "With --radl2014: L_char in m (instead of --scene)");
    app.add_option("-o,--output", output, "Directory to write into (created if absent)")->required()->type_name("DIR");
    app.add_option("--name", name, "Name of the files and the C/Fortran prefix cgd_NAME_ (default: the model file's "
                                   "stem, or radl2014)");
    app.add_option("--csv-deltas-dp", csv_deltas_dp,
                   "Delta of NAME_H.csv in primary diameters (default: the model's calibrated Delta; for Radl 2014 "
                   "3.33, 6.67, 13.3, 26.7)")
        ->delimiter(',')
        ->check(CLI::PositiveNumber);
    app.add_flag("--force", force, "Overwrite existing files of the same names in DIR");
    app.add_flag("--quiet", quiet, "Print nothing but errors");
    cgd::parse_command_line(app, argc, argv, "cgd-export");

    // ---- every input read and checked before anything is written
    if (radl == !model_path.empty())
      throw cgd::InputError("cgd-export: give a model file (MODEL.h5) or --radl2014, exactly one of them");
    if (!radl && (!scene_path.empty() || app.count("--l-char-m") || !overrides.empty()))
      throw cgd::InputError("cgd-export: --scene, --set and --l-char-m go with --radl2014 (a model file has its own L_char)");
    if (radl && scene_path.empty() == !app.count("--l-char-m"))
      throw cgd::InputError("cgd-export --radl2014: give --scene SCENE.toml or --l-char-m L, exactly one of them");
    if (!overrides.empty() && scene_path.empty()) throw cgd::InputError("cgd-export: --set needs --scene");
    if (app.count("--l-char-m") && !(l_char_m > 0 && std::isfinite(l_char_m)))
      throw cgd::InputError("cgd-export: --l-char-m " + std::to_string(l_char_m) + ": must be > 0 (m)");
    if (name.empty()) name = radl ? "radl2014" : default_name(fs::path(model_path).stem().string());
    check_name(name);

    cgd::exporter::ExportedModel e;
    cgd::exporter::Bands bands;
    std::optional<cgd::DragModel> model;
    std::vector<double> phis, deltas;
    if (!radl) {
      model = cgd::load_drag_model(model_path);
      if (model->drift)
        throw cgd::InputError("cgd-export: " + model_path + " is a drift table (curves = \"drift_table\", cgd-fit "
                              "--drift-table): the drift-velocity closure needs the cell-mean particle velocity of the "
                              "code using it and is not exported; export a model of h(phi), a(phi) or a --grid-table "
                              "table instead (docs/export.md)");
      e = cgd::exporter::from_model(*model, name, model_provenance(*model));
      bands = {model->bands.phi, model->bands.F, model->bands.H_low, model->bands.H_high};
      deltas = e.calibrated_delta_m;
    } else {
      double d = 0;
      std::vector<std::string> prov;
      if (!scene_path.empty()) {
        const cgd::Scene scene = cgd::load_scene(scene_path, overrides);
        if (!(scene.derived.l_char_m > 0))
          throw cgd::InputError(scene_path + ": the scene has no L_char (a [fluid] section and gravity are needed)");
        l_char_m = scene.derived.l_char_m;
        d = scene.particles.diameter_m;
        std::string from = "L_char of the scene " + scene_path;
        for (const std::string& o : overrides) from += " --set " + o;
        prov.push_back(from + " (docs/models.md \"Reference scales\": Schiller-Naumann u_t)");
      } else {
        prov.push_back("L_char given on the command line (--l-char-m)");
      }
      e = cgd::exporter::from_radl2014(l_char_m, d, name, prov);
      if (d > 0)
        for (double x : {3.33, 6.67, 13.3, 26.7}) deltas.push_back(x * d);
      else
        for (double F : {2.0, 1.0, 0.5, 0.25}) deltas.push_back(l_char_m / F);
    }
    if (!csv_deltas_dp.empty()) {
      if (!(e.diameter_m > 0))
        throw cgd::InputError("cgd-export: --csv-deltas-dp needs d_p: give --scene (with --radl2014)");
      deltas.clear();
      for (double x : csv_deltas_dp) deltas.push_back(x * e.diameter_m);
    }
    if (!bands.phi.empty()) {
      phis = bands.phi;
    } else {
      const double hi = e.kind == cgd::exporter::CurveKind::Radl2014 ? 0.6 : std::min(1.0, e.h.x_hi + 0.05);
      for (int i = 0; i <= 200; ++i) phis.push_back(hi * i / 200);
    }
    const cgd::DragModel* mp = model ? &*model : nullptr;
    const double lc = e.l_char_m;
    const std::vector<std::pair<std::string, std::string>> files{
        {name + ".h", cgd::exporter::c_header(e)},
        {name + ".f90", cgd::exporter::fortran_module(e)},
        {name + "_pieces.csv", cgd::exporter::pieces_csv(e)},
        {name + "_H.csv", cgd::exporter::h_table_csv(
                              e, [&](double phi, double delta) { return cgd::exporter::engine_H(mp, lc, phi, delta); },
                              phis, deltas, bands.phi.empty() ? nullptr : &bands)}};

    // ---- the output directory
    const fs::path dir(output);
    if (fs::exists(dir) && !fs::is_directory(dir))
      throw cgd::InputError(output + ": not a directory (-o names the directory to write the files into)");
    if (!fs::exists(dir) && !fs::is_directory(fs::absolute(dir).parent_path()))
      throw cgd::InputError(output + ": cannot create it: no directory " + fs::absolute(dir).parent_path().string());
    for (const auto& [file, text] : files)
      if (fs::exists(dir / file) && !force)
        throw cgd::InputError((dir / file).string() + " exists (--force overwrites it)");
    fs::create_directories(dir);
    std::vector<std::pair<fs::path, std::string>> in_dir;
    for (const auto& [file, text] : files) in_dir.emplace_back(dir / file, text);
    cgd::write_text_files_atomically(in_dir);
    if (!quiet)
      for (const auto& [file, text] : files) std::cout << "wrote " << (dir / file).string() << "\n";
    return cgd::kExitOk;
  });
  MPI_Finalize();
  return status;
}
