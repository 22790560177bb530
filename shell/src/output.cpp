#include "dembridge/shell/output.h"
#include "dembridge/shell/model.h"

#include <algorithm>
#include <fstream>
#include <hdf5.h>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace dembridge::shell
{
namespace
{
void write_dataset(hid_t file, const std::string& name, const void* data, hid_t type,
                   std::vector<hsize_t> dims)
{
  hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  H5Pset_create_intermediate_group(lcpl, 1);
  hid_t set = H5Dcreate2(file, name.c_str(), type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT);
  const bool ok = set >= 0 && H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0;
  if (set >= 0)
    H5Dclose(set);
  H5Pclose(lcpl);
  H5Sclose(space);
  if (!ok)
    throw std::runtime_error("HDF5: cannot write dataset " + name);
}

/// XDMF's name of the cell type, and the permutation from the model's node
/// order (DOLFINx's tensor-product order for quadrilaterals and hexahedra)
/// to XDMF's (counter-clockwise faces).
std::pair<std::string, std::vector<int>> xdmf_cell(bool shell, int npc)
{
  if (npc == 3)
    return {"Triangle", {0, 1, 2}};
  if (npc == 4 && shell)
    return {"Quadrilateral", {0, 1, 3, 2}};
  if (npc == 4)
    return {"Tetrahedron", {0, 1, 2, 3}};
  if (npc == 8)
    return {"Hexahedron", {0, 1, 3, 2, 4, 5, 7, 6}};
  throw std::runtime_error("XdmfWriter: cells of " + std::to_string(npc) + " nodes are not supported");
}
} // namespace

/// The shells' section fields (FEModel::section_stresses), cell-centred
/// tensors, in the order of its columns.
constexpr const char* section_fields[] = {"stress_top", "stress_bottom", "membrane_force", "bending_moment"};

struct XdmfWriter::Impl
{
  const FEModel* model = nullptr;
  std::filesystem::path xdmf, h5;
  hid_t file = -1;
  std::string cell;
  std::size_t nodes = 0, cells = 0;
  int npc = 0, bs = 6;
  bool weighted = false; // the model's energy weight is not 1 everywhere: /mesh/weight
  std::vector<double> times;
  std::vector<double> buffer; // one 3-vector field, (nodes, 3)

  void write_xdmf() const;
};

XdmfWriter::XdmfWriter(const FEModel& model, const std::filesystem::path& file)
    : _impl(std::make_unique<Impl>())
{
  auto& I = *_impl;
  I.model = &model;
  I.xdmf = file;
  I.h5 = file;
  I.h5.replace_extension(".h5");
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  I.nodes = model.num_nodes();
  I.cells = model.num_cells();
  I.npc = model.nodes_per_cell();
  I.bs = model.block_size();
  const auto [cell, perm] = xdmf_cell(model.is_shell(), I.npc);
  I.cell = cell;
  I.file = H5Fcreate(I.h5.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (I.file < 0)
    throw std::runtime_error("cannot create HDF5 file '" + I.h5.string() + "'");
  // the mesh once: reference node coordinates and the cells in XDMF's order
  const auto x = model.node_coordinates();
  write_dataset(I.file, "/mesh/geometry", x.data(), H5T_NATIVE_DOUBLE, {I.nodes, 3});
  const auto c = model.cell_nodes();
  std::vector<std::int32_t> topo(c.size());
  for (std::size_t k = 0; k < I.cells; ++k)
    for (int j = 0; j < I.npc; ++j)
      topo[k * I.npc + j] = c[k * I.npc + perm[j]];
  write_dataset(I.file, "/mesh/topology", topo.data(), H5T_NATIVE_INT32,
                {I.cells, static_cast<hsize_t>(I.npc)});
  if (model.is_shell())
  {
    const auto n = model.nodal_normals();
    write_dataset(I.file, "/mesh/normal", n.data(), H5T_NATIVE_DOUBLE, {I.nodes, 3});
  }
  const auto eta = model.weight();
  I.weighted = std::any_of(eta.begin(), eta.end(), [](double e) { return e != 1.0; });
  if (I.weighted) // a coupled model's weight, as it was when the series began
    write_dataset(I.file, "/mesh/weight", eta.data(), H5T_NATIVE_DOUBLE, {I.nodes, 1});
  H5Fflush(I.file, H5F_SCOPE_GLOBAL);
  I.write_xdmf();
}

XdmfWriter::XdmfWriter(const FEModel& model, const std::filesystem::path& file,
                       const checkpoint::Group& resume)
    : _impl(std::make_unique<Impl>())
{
  auto& I = *_impl;
  I.model = &model;
  I.xdmf = file;
  I.h5 = file;
  I.h5.replace_extension(".h5");
  I.nodes = model.num_nodes();
  I.cells = model.num_cells();
  I.npc = model.nodes_per_cell();
  I.bs = model.block_size();
  I.cell = xdmf_cell(model.is_shell(), I.npc).first;
  resume.read("times", I.times);
  const auto eta = model.weight();
  I.weighted = std::any_of(eta.begin(), eta.end(), [](double e) { return e != 1.0; });
  I.file = checkpoint::reopen_frames(I.h5, I.times.size());
  I.write_xdmf();
}

void XdmfWriter::save(const checkpoint::Group& g) const { g.write("times", _impl->times); }

std::size_t XdmfWriter::frames() const { return _impl->times.size(); }

XdmfWriter::~XdmfWriter() { close(); }

void XdmfWriter::close()
{
  if (_impl && _impl->file >= 0)
  {
    H5Fclose(_impl->file);
    _impl->file = -1;
  }
}

void XdmfWriter::write(double t, std::span<const double> u, std::span<const double> v)
{
  auto& I = *_impl;
  if (I.file < 0)
    throw std::runtime_error("XdmfWriter: file already closed");
  if (u.size() != I.nodes * I.bs || v.size() != I.nodes * I.bs)
    throw std::runtime_error("XdmfWriter: field sizes differ from the model's dofs");
  const std::string g = "/frame_" + std::to_string(I.times.size()) + "/";
  auto field = [&](const std::string& name, std::span<const double> src, int offset)
  {
    I.buffer.resize(3 * I.nodes);
    for (std::size_t i = 0; i < I.nodes; ++i)
      for (int k = 0; k < 3; ++k)
        I.buffer[3 * i + k] = src[i * I.bs + offset + k];
    write_dataset(I.file, g + name, I.buffer.data(), H5T_NATIVE_DOUBLE, {I.nodes, 3});
  };
  field("displacement", u, 0);
  field("velocity", v, 0);
  if (I.bs == 6)
  {
    field("rotation", u, 3);
    field("angular_velocity", v, 3);
    const auto sec = I.model->section_stresses(u);
    std::vector<double> tensor(9 * I.cells);
    for (int f = 0; f < 4; ++f)
    {
      for (std::size_t c = 0; c < I.cells; ++c)
        std::copy_n(&sec[36 * c + 9 * f], 9, &tensor[9 * c]);
      write_dataset(I.file, g + section_fields[f], tensor.data(), H5T_NATIVE_DOUBLE, {I.cells, 9});
    }
  }
  // flushed and the XDMF rewritten at every frame: a stopped run leaves a
  // readable file with every frame written so far
  H5Fflush(I.file, H5F_SCOPE_GLOBAL);
  I.times.push_back(t);
  I.write_xdmf();
}

void XdmfWriter::Impl::write_xdmf() const
{
  const std::string h = h5.filename().string();
  std::ostringstream x;
  x << std::setprecision(17);
  auto item = [&](const std::string& path, std::size_t rows, int cols, bool real)
  {
    x << "<DataItem Dimensions=\"" << rows << " " << cols << "\" Format=\"HDF\" NumberType=\""
      << (real ? "Float" : "Int") << "\" Precision=\"" << (real ? 8 : 4) << "\">" << h << ":" << path
      << "</DataItem>";
  };
  auto attribute = [&](const std::string& name, const std::string& path)
  {
    x << "  <Attribute Name=\"" << name << "\" AttributeType=\"Vector\" Center=\"Node\">";
    item(path, nodes, 3, true);
    x << "</Attribute>\n";
  };
  x << "<?xml version=\"1.0\"?>\n<Xdmf Version=\"3.0\">\n<Domain>\n"
    << "<Grid Name=\"shell\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t k = 0; k < times.size(); ++k)
  {
    // one grid per time step carrying every field, on the mesh written once
    x << " <Grid Name=\"shell\" GridType=\"Uniform\">\n  <Time Value=\"" << times[k] << "\"/>\n"
      << "  <Topology TopologyType=\"" << cell << "\" NumberOfElements=\"" << cells
      << "\" NodesPerElement=\"" << npc << "\">";
    item("/mesh/topology", cells, npc, false);
    x << "</Topology>\n  <Geometry GeometryType=\"XYZ\">";
    item("/mesh/geometry", nodes, 3, true);
    x << "</Geometry>\n";
    const std::string f = "/frame_" + std::to_string(k) + "/";
    attribute("displacement", f + "displacement");
    attribute("velocity", f + "velocity");
    if (bs == 6)
    {
      attribute("rotation", f + "rotation");
      attribute("angular_velocity", f + "angular_velocity");
      attribute("normal", "/mesh/normal");
      for (const char* name : section_fields)
      {
        x << "  <Attribute Name=\"" << name << "\" AttributeType=\"Tensor\" Center=\"Cell\">";
        item(f + name, cells, 9, true);
        x << "</Attribute>\n";
      }
    }
    if (weighted)
    {
      x << "  <Attribute Name=\"weight\" AttributeType=\"Scalar\" Center=\"Node\">";
      item("/mesh/weight", nodes, 1, true);
      x << "</Attribute>\n";
    }
    x << " </Grid>\n";
  }
  x << "</Grid>\n</Domain>\n</Xdmf>\n";
  const auto tmp = xdmf.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << x.str();
    if (!out.flush())
      throw std::runtime_error("cannot write '" + tmp + "'");
  }
  std::filesystem::rename(tmp, xdmf);
}

} // namespace dembridge::shell
