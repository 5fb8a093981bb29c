// run.xmf: the ParaView entry point of a run directory (XDMF 3, light data only; the heavy data
// stays in the snapshot files, referenced as "<file>:/<dataset>").
//
// Layout: a Temporal collection; per frame a Spatial collection holding
//   "particles": Polyvertex topology, XYZ geometry from /particles/position, node attributes;
//   "fluid":     3DCoRectMesh over the *node* grid (n_z+1, n_y+1, n_x+1), ORIGIN_DXDYDZ geometry,
//                cell attributes void_fraction, pressure (n_z, n_y, n_x) and velocity (…, 3).
// XDMF lists CoRectMesh dimensions, origin and spacing slowest axis first, i.e. (z, y, x), which
// matches the (n_z, n_y, n_x) layout of the arrays in the file.
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "core/error.hpp"
#include "core/output.hpp"

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

void particles_grid(std::ostringstream& x, const XdmfFrame& fr) {
  const std::string n = std::to_string(fr.particle_count);
  const std::string& h5 = fr.snapshot_file;
  const std::string in = "          ";
  x << in << "<Grid Name=\"particles\" GridType=\"Uniform\">\n"
    << in << "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
    << "\" NodesPerElement=\"1\"/>\n"
    << in << "  <Geometry GeometryType=\"XYZ\">\n"
    << in << "    " << hdf_item(n + " 3", h5, "/particles/position") << "\n"
    << in << "  </Geometry>\n";
  auto attribute = [&](const char* name, const char* type, const std::string& dims, const char* number_type) {
    x << in << "  <Attribute Name=\"" << name << "\" AttributeType=\"" << type << "\" Center=\"Node\">\n"
      << in << "    " << hdf_item(dims, h5, std::string("/particles/") + name, number_type) << "\n"
      << in << "  </Attribute>\n";
  };
  attribute("velocity", "Vector", n + " 3", "Float");
  attribute("diameter", "Scalar", n, "Float");
  attribute("id", "Scalar", n, "Int");
  if (fr.has_angular_velocity) attribute("angular_velocity", "Vector", n + " 3", "Float");
  x << in << "</Grid>\n";
}

void fluid_grid(std::ostringstream& x, const XdmfFrame& fr) {
  const int nx = fr.cells[0], ny = fr.cells[1], nz = fr.cells[2];
  const std::string cells = std::to_string(nz) + " " + std::to_string(ny) + " " + std::to_string(nx);
  const std::string nodes =
      std::to_string(nz + 1) + " " + std::to_string(ny + 1) + " " + std::to_string(nx + 1);
  const std::string& h5 = fr.snapshot_file;
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
  auto attribute = [&](const char* name, const char* type, const std::string& dims) {
    x << in << "  <Attribute Name=\"" << name << "\" AttributeType=\"" << type << "\" Center=\"Cell\">\n"
      << in << "    " << hdf_item(dims, h5, std::string("/fluid/") + name) << "\n"
      << in << "  </Attribute>\n";
  };
  attribute("void_fraction", "Scalar", cells);
  attribute("pressure", "Scalar", cells);
  attribute("velocity", "Vector", cells + " 3");
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
    if (fr.particle_count > 0) particles_grid(x, fr);  // an empty polyvertex grid upsets the readers
    if (fr.has_fluid) fluid_grid(x, fr);
    x << "      </Grid>\n";
  }
  x << "    </Grid>\n"
    << "  </Domain>\n"
    << "</Xdmf>\n";
  const std::string text = x.str();

  // Atomically: write a temporary file in the same folder, fsync, rename.
  const std::string final_path = (std::filesystem::path(run_dir) / "run.xmf").string();
  const std::string tmp_path = final_path + ".tmp";
  auto fail = [&](int error) {
    std::remove(tmp_path.c_str());
    throw RunError(final_path + ": cannot write (" + std::strerror(error) + ")");
  };
  const int fd = ::open(tmp_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) fail(errno);
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      ::close(fd);
      fail(error);
    }
    written += static_cast<std::size_t>(n);
  }
  int error = ::fsync(fd) != 0 ? errno : 0;
  if (::close(fd) != 0 && error == 0) error = errno;
  if (error != 0) fail(error);
  if (std::rename(tmp_path.c_str(), final_path.c_str()) != 0) fail(errno);
}

}  // namespace cgd::schema
