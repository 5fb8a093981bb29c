// run.xmf: the ParaView entry point of a run directory (XDMF 3, light data only; the heavy data
// stays in the snapshot files, referenced as "<file>:/<dataset>").
//
// Layout: a Temporal collection; per frame a Spatial collection holding
//   "particles": Polyvertex topology, XYZ geometry from /particles/position, and one node attribute per
//                dataset of the snapshot's /particles group (velocity, diameter, id, and whatever the run
//                simulates: angular_velocity, drag_coefficient beta_p, fluid_velocity, pressure_gradient);
//   "fluid":     3DCoRectMesh over the *node* grid (n_z+1, n_y+1, n_x+1), ORIGIN_DXDYDZ geometry, and one
//                cell attribute per dataset of /fluid (void_fraction, pressure, velocity, eps_velocity).
// The attributes are read from each snapshot file (the datasets it holds), so the file and its XDMF
// entry cannot disagree: what h5ls shows, ParaView shows.
// XDMF lists CoRectMesh dimensions, origin and spacing slowest axis first, i.e. (z, y, x), which
// matches the (n_z, n_y, n_x) layout of the arrays in the file.
#include <hdf5.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <sstream>
#include <string_view>

#include "core/error.hpp"
#include "core/h5.hpp"
#include "core/xdmf.hpp"
#include "core/schema/snapshot.hpp"
#include "core/text_file.hpp"

namespace cgd::schema {
namespace {

/// Shortest text that reads back as the same double.
std::string number(double v) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, v);
  return std::string(text, result.ptr);
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// A DataItem referring to a dataset of the snapshot file.
std::string hdf_item(const std::string& dims, const std::string& file, const std::string& dataset,
                     const char* number_type = "Float") {
  return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" + number_type +
         "\" Precision=\"8\" Format=\"HDF\">" + xml_escape(file) + ":" + dataset + "</DataItem>";
}

/// One dataset of a snapshot group, as XDMF needs it.
struct Field {
  std::string name;
  std::vector<hsize_t> dims;  // (rows) scalar, (rows, 3) vector; fluid: (n_z, n_y, n_x[, 3])
  bool integer = false;
};

/// The datasets of the /particles and /fluid groups of a snapshot file, in name order.
struct SnapshotFields {
  std::vector<Field> particles, fluid;
};

std::vector<Field> group_fields(hid_t file, const char* group, const std::string& path) {
  std::vector<Field> out;
  if (H5Lexists(file, group, H5P_DEFAULT) <= 0) return out;
  const hid_t g = H5Gopen2(file, group, H5P_DEFAULT);
  if (g < 0) throw RunError(path + ": cannot open " + group + " to list its fields for run.xmf");
  H5G_info_t info;
  H5Gget_info(g, &info);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    char name[256];
    if (H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT) < 0)
      continue;
    const hid_t d = H5Dopen2(g, name, H5P_DEFAULT);
    if (d < 0) continue;  // a subgroup: no field
    Field f{name, {}, false};
    const hid_t space = H5Dget_space(d), type = H5Dget_type(d);
    f.dims.resize(static_cast<std::size_t>(std::max(H5Sget_simple_extent_ndims(space), 0)));
    H5Sget_simple_extent_dims(space, f.dims.data(), nullptr);
    f.integer = H5Tget_class(type) == H5T_INTEGER;
    H5Tclose(type);
    H5Sclose(space);
    H5Dclose(d);
    out.push_back(std::move(f));
  }
  H5Gclose(g);
  return out;
}

/// The fields of the snapshot at `path`, read once per file version: run.xmf is rewritten after every
/// snapshot, and a run of a thousand snapshots must not reopen them all each time.
const SnapshotFields& snapshot_fields(const std::string& path) {
  static std::map<std::string, std::pair<std::filesystem::file_time_type, SnapshotFields>> cache;
  std::error_code ec;
  const auto written = std::filesystem::last_write_time(path, ec);
  if (ec)
    throw RunError(path + ": cannot read the snapshot to list its fields for run.xmf (" + ec.message() + ")");
  auto it = cache.find(path);
  if (it != cache.end() && it->second.first == written) return it->second.second;
  h5::File file = h5::File::open_read(path, MPI_COMM_SELF);
  SnapshotFields fields{group_fields(file.id(), names::kParticles, path), group_fields(file.id(), names::kFluid, path)};
  file.close();
  return cache.insert_or_assign(path, std::make_pair(written, std::move(fields))).first->second.second;
}

std::string dims_text(const std::vector<hsize_t>& dims) {
  std::string out;
  for (const hsize_t d : dims) out += (out.empty() ? "" : " ") + std::to_string(d);
  return out;
}

/// One attribute per field: Vector when the last axis has 3 components beyond the grid's axes.
void attributes(std::ostringstream& x, const std::vector<Field>& fields, const std::string& h5,
                const char* group, std::size_t grid_rank, const char* center, const std::string& indent) {
  for (const Field& f : fields) {
    if (std::string(group) + "/" + f.name == names::kPosition) continue;  // the geometry
    const bool vector = f.dims.size() == grid_rank + 1 && f.dims.back() == 3;
    if (f.dims.size() != grid_rank && !vector)
      continue;  // no such field in the schema; XDMF could not show it
    x << indent << "  <Attribute Name=\"" << xml_escape(f.name) << "\" AttributeType=\""
      << (vector ? "Vector" : "Scalar") << "\" Center=\"" << center << "\">\n"
      << indent << "    "
      << hdf_item(dims_text(f.dims), h5, std::string(group) + "/" + f.name, f.integer ? "Int" : "Float")
      << "\n"
      << indent << "  </Attribute>\n";
  }
}

void particles_grid(std::ostringstream& x, const XdmfFrame& fr, const SnapshotFields& fields) {
  const std::string n = std::to_string(fr.particle_count);
  const std::string& h5 = fr.snapshot_file;
  const std::string in = "          ";
  x << in << "<Grid Name=\"particles\" GridType=\"Uniform\">\n"
    << in << "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
    << "\" NodesPerElement=\"1\"/>\n"
    << in << "  <Geometry GeometryType=\"XYZ\">\n"
    << in << "    " << hdf_item(n + " 3", h5, names::kPosition) << "\n"
    << in << "  </Geometry>\n";
  attributes(x, fields.particles, h5, names::kParticles, 1, "Node", in);
  x << in << "</Grid>\n";
}

void fluid_grid(std::ostringstream& x, const XdmfFrame& fr, const SnapshotFields& fields) {
  const int nx = fr.cells[0], ny = fr.cells[1], nz = fr.cells[2];
  const std::string nodes =
      std::to_string(nz + 1) + " " + std::to_string(ny + 1) + " " + std::to_string(nx + 1);
  const std::string in = "          ";
  x << in << "<Grid Name=\"fluid\" GridType=\"Uniform\">\n"
    << in << "  <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << nodes << "\"/>\n"
    << in << "  <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
    << in
    << "    <DataItem Name=\"Origin\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">"
    << number(fr.origin_m[2]) << " " << number(fr.origin_m[1]) << " " << number(fr.origin_m[0])
    << "</DataItem>\n"
    << in
    << "    <DataItem Name=\"Spacing\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">"
    << number(fr.spacing_m[2]) << " " << number(fr.spacing_m[1]) << " " << number(fr.spacing_m[0])
    << "</DataItem>\n"
    << in << "  </Geometry>\n";
  attributes(x, fields.fluid, fr.snapshot_file, names::kFluid, 3, "Cell", in);
  x << in << "</Grid>\n";
}

}  // namespace

void write_xdmf(const std::string& run_dir, const std::vector<XdmfFrame>& frames) {
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
    << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<Xdmf xmlns:xi=\"http://www.w3.org/2001/XInclude\" Version=\"3.0\">\n"
    << "  <Domain>\n"
    << "    <Grid Name=\"run\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const XdmfFrame& fr = frames[i];
    x << "      <Grid Name=\"frame_" << i << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
      << "        <Time Value=\"" << number(fr.time_s) << "\"/>\n";
    const SnapshotFields& fields =
        snapshot_fields((std::filesystem::path(run_dir) / fr.snapshot_file).string());
    if (fr.particle_count > 0) particles_grid(x, fr, fields);  // an empty polyvertex grid upsets the readers
    if (fr.has_fluid) fluid_grid(x, fr, fields);
    x << "      </Grid>\n";
  }
  x << "    </Grid>\n"
    << "  </Domain>\n"
    << "</Xdmf>\n";
  const std::string text = x.str();

  write_text_atomically(std::filesystem::path(run_dir) / "run.xmf", text);
}

}  // namespace cgd::schema
