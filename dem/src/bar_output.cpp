// The bars' XDMF + HDF5 series (output.h: BarWriter).
#include "dembridge/dem/output.h"

#include "hdf5_write.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace dembridge::dem
{
using impl::write_dataset;

BarWriter::BarWriter(const std::filesystem::path& file, const Bars& bars)
    : _xdmf(file), _h5(file), _nodes(bars.nodes()), _elements(bars.elements())
{
  _h5.replace_extension(".h5");
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  _file = H5Fcreate(_h5.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (_file < 0)
    throw std::runtime_error("cannot create HDF5 file '" + _h5.string() + "'");
  std::vector<std::int32_t> ends(2 * _elements);
  for (std::size_t e = 0; e < _elements; ++e)
  {
    ends[2 * e] = bars.a[e];
    ends[2 * e + 1] = bars.b[e];
  }
  write_dataset(_file, "/elements", ends.data(), H5T_NATIVE_INT32, {_elements, 2});
  write_xdmf();
}

BarWriter::BarWriter(const std::filesystem::path& file, const Bars& bars, const checkpoint::Group& resume)
    : _xdmf(file), _h5(file), _nodes(bars.nodes()), _elements(bars.elements())
{
  _h5.replace_extension(".h5");
  resume.read("times", _times);
  _file = checkpoint::reopen_frames(_h5, _times.size());
  write_xdmf();
}

BarWriter::~BarWriter() { close(); }

void BarWriter::close()
{
  if (_file >= 0)
  {
    H5Fclose(_file);
    _file = -1;
  }
}

void BarWriter::save(const checkpoint::Group& g) const { g.write("times", _times); }

void BarWriter::write(double t, const Bars& bars)
{
  if (_file < 0)
    throw std::runtime_error("BarWriter: file closed");
  const std::string g = "/frame_" + std::to_string(_times.size()) + "/";
  std::vector<double> u(3 * _nodes), slip(_elements, 0.0), broken(_elements), plastic(_elements);
  std::vector<int> count(_elements, 0);
  for (std::size_t i = 0; i < 3 * _nodes; ++i)
    u[i] = bars.x[i] - bars.x0[i];
  for (std::size_t k = 0; k < bars.bonds(); ++k)
  {
    slip[bars.element[k]] += std::abs(bars.slip[k]);
    ++count[bars.element[k]];
  }
  for (std::size_t e = 0; e < _elements; ++e)
  {
    slip[e] = count[e] > 0 ? slip[e] / count[e] : 0.0;
    broken[e] = bars.broken[e];
    plastic[e] = bars.plastic[e];
  }
  write_dataset(_file, g + "position", bars.x.data(), H5T_NATIVE_DOUBLE, {_nodes, 3});
  write_dataset(_file, g + "displacement", u.data(), H5T_NATIVE_DOUBLE, {_nodes, 3});
  write_dataset(_file, g + "velocity", bars.v.data(), H5T_NATIVE_DOUBLE, {_nodes, 3});
  write_dataset(_file, g + "axial_force", bars.force.data(), H5T_NATIVE_DOUBLE, {_elements});
  write_dataset(_file, g + "plastic_strain", plastic.data(), H5T_NATIVE_DOUBLE, {_elements});
  write_dataset(_file, g + "slip", slip.data(), H5T_NATIVE_DOUBLE, {_elements});
  write_dataset(_file, g + "broken", broken.data(), H5T_NATIVE_DOUBLE, {_elements});
  H5Fflush(_file, H5F_SCOPE_GLOBAL);
  _times.push_back(t);
  write_xdmf();
}

void BarWriter::write_xdmf() const
{
  const std::string h5 = _h5.filename().string();
  std::ostringstream x;
  x << std::setprecision(17);
  x << "<?xml version=\"1.0\"?>\n<Xdmf Version=\"3.0\">\n<Domain>\n"
    << "<Grid Name=\"bars\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t k = 0; k < _times.size(); ++k)
  {
    const std::string at = h5 + ":/frame_" + std::to_string(k) + "/";
    auto attr = [&](const std::string& name, const std::string& type, const std::string& centre, std::size_t n,
                    bool vector)
    {
      x << "  <Attribute Name=\"" << name << "\" AttributeType=\"" << type << "\" Center=\"" << centre << "\">\n"
        << "   <DataItem Dimensions=\"" << n << (vector ? " 3" : "")
        << "\" Format=\"HDF\" NumberType=\"Float\" Precision=\"8\">" << at << name << "</DataItem>\n  </Attribute>\n";
    };
    x << " <Grid Name=\"bars\" GridType=\"Uniform\">\n  <Time Value=\"" << _times[k] << "\"/>\n"
      << "  <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\"" << _elements
      << "\">\n   <DataItem Dimensions=\"" << _elements << " 2\" Format=\"HDF\" NumberType=\"Int\" Precision=\"4\">"
      << h5 << ":/elements</DataItem>\n  </Topology>\n"
      << "  <Geometry GeometryType=\"XYZ\">\n   <DataItem Dimensions=\"" << _nodes
      << " 3\" Format=\"HDF\" NumberType=\"Float\" Precision=\"8\">" << at << "position</DataItem>\n  </Geometry>\n";
    attr("displacement", "Vector", "Node", _nodes, true);
    attr("velocity", "Vector", "Node", _nodes, true);
    attr("axial_force", "Scalar", "Cell", _elements, false);
    attr("plastic_strain", "Scalar", "Cell", _elements, false);
    attr("slip", "Scalar", "Cell", _elements, false);
    attr("broken", "Scalar", "Cell", _elements, false);
    x << " </Grid>\n";
  }
  x << "</Grid>\n</Domain>\n</Xdmf>\n";
  impl::replace_text_file(_xdmf, x.str());
}

} // namespace dembridge::dem
