#include "dembridge/dem/output.h"

#include "hdf5_write.h"

#include <cmath>
#include <fstream>
#include <hdf5.h>
#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace dembridge::dem
{
using impl::write_dataset;

ParticleWriter::ParticleWriter(const std::filesystem::path& file, const Links& links,
                               std::size_t particles, bool cracks)
    : _xdmf(file), _h5(file), _cracks(cracks), _n(particles)
{
  _h5.replace_extension(".h5");
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  _file = H5Fcreate(_h5.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (_file < 0)
    throw std::runtime_error("cannot create HDF5 file '" + _h5.string() + "'");
  // the vertex cells' index list, 0 .. n - 1 (the Polyvertex topology's)
  std::vector<std::int32_t> vertices(particles);
  for (std::size_t i = 0; i < particles; ++i)
    vertices[i] = static_cast<std::int32_t>(i);
  write_dataset(_file, "/vertices", vertices.data(), H5T_NATIVE_INT32, {particles, 1});
  _initial_links.assign(particles, 0);
  for (std::size_t k = 0; k < links.size(); ++k)
  {
    ++_initial_links[links.a[k]];
    ++_initial_links[links.b[k]];
  }
  write_xdmf();
}

ParticleWriter::ParticleWriter(const std::filesystem::path& file, const Links& links,
                               std::size_t particles, bool cracks, const checkpoint::Group& resume)
    : _xdmf(file), _h5(file), _cracks(cracks), _n(particles)
{
  _h5.replace_extension(".h5");
  resume.read("times", _times);
  std::vector<std::int64_t> broken;
  resume.read("broken_count", broken);
  if (broken.size() != _times.size())
    resume.fail("broken_count", "not one count per frame");
  _broken_count.assign(broken.begin(), broken.end());
  _file = checkpoint::reopen_frames(_h5, _times.size());
  _initial_links.assign(particles, 0);
  for (std::size_t k = 0; k < links.size(); ++k)
  {
    ++_initial_links[links.a[k]];
    ++_initial_links[links.b[k]];
  }
  write_xdmf();
}

void ParticleWriter::save(const checkpoint::Group& g) const
{
  g.write("times", _times);
  std::vector<std::int64_t> broken(_broken_count.begin(), _broken_count.end());
  g.write("broken_count", broken);
}

ParticleWriter::~ParticleWriter() { close(); }

void ParticleWriter::close()
{
  if (_file >= 0)
  {
    H5Fclose(_file);
    _file = -1;
  }
}

void ParticleWriter::add_surface(const std::string& name, SurfaceMesh mesh)
{
  if (_file < 0)
    throw std::runtime_error("ParticleWriter: file closed");
  if (name.empty() || name == "particles" || name == "cracks" || name.find_first_of("/. ") != std::string::npos)
    throw std::runtime_error("ParticleWriter: surface name '" + name + "': not empty, particles or cracks, no '/', '.' or ' '");
  for (const auto& q : _surfaces)
    if (q.name == name)
      throw std::runtime_error("ParticleWriter: surface '" + name + "' added twice");
  const std::string set = "/" + name + "_triangles";
  if (H5Lexists(_file, set.c_str(), H5P_DEFAULT) <= 0) // a resumed series has it
    write_dataset(_file, set, mesh.triangles.data(), H5T_NATIVE_INT32, {mesh.triangles.size() / 3, 3});
  _surfaces.push_back({name, std::move(mesh)});
  write_xdmf();
}

void ParticleWriter::write(double t, const Particles& p, const Links& l, std::span<const RigidBody> bodies)
{
  if (_file < 0)
    throw std::runtime_error("ParticleWriter: file closed");
  if (bodies.size() != _surfaces.size())
    throw std::runtime_error("ParticleWriter: " + std::to_string(bodies.size()) + " bodies for "
                             + std::to_string(_surfaces.size()) + " surfaces");
  const std::size_t n = p.size(), k = _times.size();
  const std::string g = "/frame_" + std::to_string(k) + "/";
  std::vector<double> u(3 * n), damage(n, 0.0);
  for (std::size_t i = 0; i < 3 * n; ++i)
    u[i] = p.x[i] - p.x0[i];
  std::vector<std::int32_t> broken;
  for (std::size_t q = 0; q < l.size(); ++q)
    if (l.state[q] != LinkState::intact)
    {
      damage[l.a[q]] += 1.0;
      damage[l.b[q]] += 1.0;
      broken.push_back(l.a[q]);
      broken.push_back(l.b[q]);
    }
  for (std::size_t i = 0; i < n; ++i)
    damage[i] = _initial_links[i] > 0 ? damage[i] / _initial_links[i] : 0.0;
  write_dataset(_file, g + "position", p.x.data(), H5T_NATIVE_DOUBLE, {n, 3});
  write_dataset(_file, g + "radius", p.r.data(), H5T_NATIVE_DOUBLE, {n});
  write_dataset(_file, g + "displacement", u.data(), H5T_NATIVE_DOUBLE, {n, 3});
  write_dataset(_file, g + "velocity", p.v.data(), H5T_NATIVE_DOUBLE, {n, 3});
  write_dataset(_file, g + "damage", damage.data(), H5T_NATIVE_DOUBLE, {n});
  if (_cracks)
    write_dataset(_file, g + "broken_links", broken.data(), H5T_NATIVE_INT32, {broken.size() / 2, 2});
  for (std::size_t s = 0; s < _surfaces.size(); ++s)
  {
    const RigidBody& b = bodies[s];
    const SurfaceMesh& mesh = _surfaces[s].mesh;
    const auto w = b.fixed ? std::array<double, 3>{0, 0, 0} : b.omega();
    std::vector<double> x(mesh.x.size()), v(mesh.x.size());
    for (std::size_t i = 0; i < mesh.vertices(); ++i)
    {
      // world velocity v + omega x (x - x_c)
      const auto xw = b.to_world({mesh.x[3 * i], mesh.x[3 * i + 1], mesh.x[3 * i + 2]});
      const std::array<double, 3> d{xw[0] - b.x[0], xw[1] - b.x[1], xw[2] - b.x[2]};
      const std::array<double, 3> wd{w[1] * d[2] - w[2] * d[1], w[2] * d[0] - w[0] * d[2], w[0] * d[1] - w[1] * d[0]};
      for (int c = 0; c < 3; ++c)
      {
        x[3 * i + c] = xw[c];
        v[3 * i + c] = b.v[c] + wd[c];
      }
    }
    const std::string name = g + _surfaces[s].name + "_";
    write_dataset(_file, name + "position", x.data(), H5T_NATIVE_DOUBLE, {mesh.vertices(), 3});
    write_dataset(_file, name + "velocity", v.data(), H5T_NATIVE_DOUBLE, {mesh.vertices(), 3});
  }
  H5Fflush(_file, H5F_SCOPE_GLOBAL);
  _times.push_back(t);
  _broken_count.push_back(broken.size() / 2);
  write_xdmf();
}

void ParticleWriter::write_xdmf() const
{
  const std::string h5 = _h5.filename().string();
  std::ostringstream x;
  x << std::setprecision(17);
  x << "<?xml version=\"1.0\"?>\n<Xdmf Version=\"3.0\">\n<Domain>\n"
    << "<Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  auto attr = [&](const std::string& name, const std::string& type, std::size_t k, int comps)
  {
    x << "  <Attribute Name=\"" << name << "\" AttributeType=\"" << type << "\" Center=\"Node\">\n"
      << "   <DataItem Dimensions=\"" << _n << (comps > 1 ? " 3" : "")
      << "\" Format=\"HDF\" NumberType=\"Float\" Precision=\"8\">" << h5 << ":/frame_" << k
      << "/" << name << "</DataItem>\n  </Attribute>\n";
  };
  for (std::size_t k = 0; k < _times.size(); ++k)
  {
    x << " <Grid Name=\"particles\" GridType=\"Uniform\">\n  <Time Value=\"" << _times[k] << "\"/>\n"
      << "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << _n
      << "\" NodesPerElement=\"1\">\n   <DataItem Dimensions=\"" << _n
      << " 1\" Format=\"HDF\" NumberType=\"Int\" Precision=\"4\">" << h5 << ":/vertices</DataItem>\n"
      << "  </Topology>\n"
      << "  <Geometry GeometryType=\"XYZ\">\n   <DataItem Dimensions=\"" << _n
      << " 3\" Format=\"HDF\" NumberType=\"Float\" Precision=\"8\">" << h5 << ":/frame_" << k
      << "/position</DataItem>\n  </Geometry>\n";
    attr("radius", "Scalar", k, 1);
    attr("displacement", "Vector", k, 3);
    attr("velocity", "Vector", k, 3);
    attr("damage", "Scalar", k, 1);
    x << " </Grid>\n";
  }
  x << "</Grid>\n";
  if (_cracks)
  {
    x << "<Grid Name=\"cracks\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (std::size_t k = 0; k < _times.size(); ++k)
    {
      x << " <Grid Name=\"cracks\" GridType=\"Uniform\">\n  <Time Value=\"" << _times[k] << "\"/>\n";
      if (_broken_count[k] > 0)
        x << "  <Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" NumberOfElements=\""
          << _broken_count[k] << "\">\n   <DataItem Dimensions=\"" << _broken_count[k]
          << " 2\" Format=\"HDF\" NumberType=\"Int\" Precision=\"4\">" << h5 << ":/frame_" << k
          << "/broken_links</DataItem>\n  </Topology>\n";
      else
        x << "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"0\"/>\n";
      x << "  <Geometry GeometryType=\"XYZ\">\n   <DataItem Dimensions=\"" << _n
        << " 3\" Format=\"HDF\" NumberType=\"Float\" Precision=\"8\">" << h5 << ":/frame_" << k
        << "/position</DataItem>\n  </Geometry>\n </Grid>\n";
    }
    x << "</Grid>\n";
  }
  for (const auto& surface : _surfaces)
  {
    const std::size_t nv = surface.mesh.vertices(), nt = surface.mesh.triangles.size() / 3;
    const std::string& name = surface.name;
    x << "<Grid Name=\"" << name << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (std::size_t k = 0; k < _times.size(); ++k)
    {
      const std::string at = h5 + ":/frame_" + std::to_string(k) + "/" + name + "_";
      x << " <Grid Name=\"" << name << "\" GridType=\"Uniform\">\n  <Time Value=\"" << _times[k] << "\"/>\n"
        << "  <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << nt << "\">\n   <DataItem Dimensions=\""
        << nt << " 3\" Format=\"HDF\" NumberType=\"Int\" Precision=\"4\">" << h5 << ":/" << name
        << "_triangles</DataItem>\n  </Topology>\n"
        << "  <Geometry GeometryType=\"XYZ\">\n   <DataItem Dimensions=\"" << nv
        << " 3\" Format=\"HDF\" NumberType=\"Float\" Precision=\"8\">" << at << "position</DataItem>\n  </Geometry>\n"
        << "  <Attribute Name=\"velocity\" AttributeType=\"Vector\" Center=\"Node\">\n   <DataItem Dimensions=\"" << nv
        << " 3\" Format=\"HDF\" NumberType=\"Float\" Precision=\"8\">" << at << "velocity</DataItem>\n  </Attribute>\n"
        << " </Grid>\n";
    }
    x << "</Grid>\n";
  }
  x << "</Domain>\n</Xdmf>\n";
  impl::replace_text_file(_xdmf, x.str());
}

} // namespace dembridge::dem
