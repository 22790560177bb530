#include "dembridge/shell/output.h"
#include "dembridge/shell/model.h"

#include <basix/finite-element.h>
#include <dolfinx/fem/Function.h>
#include <dolfinx/fem/FunctionSpace.h>
#include <dolfinx/fem/utils.h>
#include <dolfinx/io/XDMFFile.h>
#include <dolfinx/mesh/Mesh.h>
#include <dolfinx/mesh/cell_types.h>
#include <stdexcept>

namespace dembridge::shell
{
using dolfinx::fem::Function;

struct XdmfWriter::Impl
{
  std::unique_ptr<dolfinx::io::XDMFFile> file;
  std::vector<std::shared_ptr<Function<double>>> fields; // 3-vector P1 fields
  std::vector<std::int32_t> node_map;                    // model node -> field node
  int bs = 6;
  std::vector<double> normals;
};

XdmfWriter::XdmfWriter(const FEModel& model, const std::filesystem::path& file)
    : _impl(std::make_unique<Impl>())
{
  auto& I = *_impl;
  auto mesh = model.mesh();
  if (file.has_parent_path())
    std::filesystem::create_directories(file.parent_path());
  I.file = std::make_unique<dolfinx::io::XDMFFile>(mesh->comm(), file, "w");
  I.file->write_mesh(*mesh);
  auto e = basix::create_element(
      basix::element::family::P,
      dolfinx::mesh::cell_type_to_basix_type(mesh->topology().cell_type()), 1,
      basix::element::lagrange_variant::equispaced);
  auto V3 = std::make_shared<dolfinx::fem::FunctionSpace>(
      dolfinx::fem::create_functionspace(mesh, e, 3));
  I.bs = model.block_size();
  std::vector<std::string> names = {"displacement", "velocity"};
  if (model.is_shell())
    names.insert(names.end(), {"rotation", "angular_velocity", "normal"});
  for (auto& n : names)
  {
    auto f = std::make_shared<Function<double>>(V3);
    f->name = n;
    I.fields.push_back(f);
  }
  // node map through the cells (both spaces are P1 on the same cells)
  const auto& l6 = model.function_space()->dofmap()->list();
  const auto& l3 = V3->dofmap()->list();
  I.node_map.assign(model.num_nodes(), -1);
  for (std::int32_t c = 0; c < l6.num_nodes(); ++c)
  {
    auto a = l6.links(c), b = l3.links(c);
    for (std::size_t k = 0; k < a.size(); ++k)
      I.node_map[a[k]] = b[k];
  }
  if (model.is_shell())
  {
    auto n = model.nodal_normals();
    I.normals.assign(n.begin(), n.end());
  }
}

XdmfWriter::~XdmfWriter() { close(); }

void XdmfWriter::close()
{
  if (_impl && _impl->file)
  {
    _impl->file->close();
    _impl->file.reset();
  }
}

void XdmfWriter::write(double t, std::span<const double> u, std::span<const double> v)
{
  auto& I = *_impl;
  if (!I.file)
    throw std::runtime_error("XdmfWriter: file already closed");
  const std::size_t nn = I.node_map.size();
  if (u.size() != nn * I.bs || v.size() != nn * I.bs)
    throw std::runtime_error("XdmfWriter: field sizes differ from the model's dofs");
  auto fill = [&](std::size_t field, std::span<const double> src, int offset, int stride)
  {
    auto x = I.fields[field]->x()->mutable_array();
    for (std::size_t i = 0; i < nn; ++i)
      for (int k = 0; k < 3; ++k)
        x[3 * I.node_map[i] + k] = src[i * stride + offset + k];
  };
  fill(0, u, 0, I.bs);
  fill(1, v, 0, I.bs);
  if (I.bs == 6)
  {
    fill(2, u, 3, 6);
    fill(3, v, 3, 6);
    fill(4, I.normals, 0, 3);
  }
  for (auto& f : I.fields)
    I.file->write_function(*f, t);
}

} // namespace dembridge::shell
