#include "dembridge/shell/model.h"

#include "shell_quadrilateral.h"
#include "shell_triangle.h"
#include "solid_hexahedron.h"
#include "solid_tetrahedron.h"

#include <algorithm>
#include <numbers>
#include <numeric>
#include <cmath>
#include <dolfinx/fem/Constant.h>
#include <dolfinx/fem/Form.h>
#include <dolfinx/fem/Function.h>
#include <dolfinx/fem/FunctionSpace.h>
#include <dolfinx/fem/assembler.h>
#include <dolfinx/fem/petsc.h>
#include <dolfinx/fem/utils.h>
#include <dolfinx/la/petsc.h>
#include <dolfinx/mesh/Mesh.h>
#include <dolfinx/mesh/Topology.h>
#include <dolfinx/mesh/utils.h>
#include <petscksp.h>
#include <set>
#include <sstream>
#include <stdexcept>

namespace dembridge::shell
{
using dolfinx::fem::Constant;
using dolfinx::fem::Form;
using dolfinx::fem::Function;
using dolfinx::fem::FunctionSpace;

void validate(const Material& m, bool shell)
{
  auto fail = [](const std::string& what, double v, const std::string& allowed)
  {
    std::ostringstream s;
    s << what << " = " << v << ": must be " << allowed;
    throw std::runtime_error(s.str());
  };
  if (!(m.youngs_modulus > 0.0) || !std::isfinite(m.youngs_modulus))
    fail("Young's modulus E", m.youngs_modulus, "> 0 Pa");
  if (!(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5))
    fail("Poisson's ratio nu", m.poisson_ratio, "in (-1, 0.5)");
  if (!(m.density > 0.0) || !std::isfinite(m.density))
    fail("density rho", m.density, "> 0 kg/m^3");
  if (shell)
  {
    if (!(m.thickness > 0.0) || !std::isfinite(m.thickness))
      fail("thickness h", m.thickness, "> 0 m");
    if (!(m.shear_factor > 0.0) || !std::isfinite(m.shear_factor))
      fail("shear factor k", m.shear_factor, "> 0");
    if (!(m.drilling > 0.0) || !std::isfinite(m.drilling))
      fail("drilling penalty", m.drilling, "> 0 (fraction of G h)");
  }
}

std::array<std::array<double, 3>, 2> section_sums(const Reinforcement& r)
{
  std::array<std::array<double, 3>, 2> sums{};
  for (const BarLayer& l : r.layers)
  {
    const double a = std::numbers::pi * l.diameter * l.diameter / (4.0 * l.spacing);
    auto& s = sums[l.direction == 0 ? 0 : 1];
    s[0] += a;
    s[1] += a * l.z;
    s[2] += a * l.z * l.z;
  }
  return sums;
}

void validate(const Reinforcement& r, double thickness)
{
  auto fail = [](const std::string& what, double v, const std::string& allowed)
  {
    std::ostringstream s;
    s << "reinforcement: " << what << " = " << v << ": must be " << allowed;
    throw std::runtime_error(s.str());
  };
  if (!(r.youngs_modulus > 0.0) || !std::isfinite(r.youngs_modulus))
    fail("steel Young's modulus E_s", r.youngs_modulus, "> 0 Pa");
  if (!(r.density > 0.0) || !std::isfinite(r.density))
    fail("steel density rho_s", r.density, "> 0 kg/m^3");
  const auto& d = r.direction;
  const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(len > 0.0) || !std::isfinite(len))
    fail("length of the bar direction", len, "> 0 (a global vector whose projection is d1)");
  for (std::size_t k = 0; k < r.layers.size(); ++k)
  {
    const BarLayer& l = r.layers[k];
    const std::string name = "layer " + std::to_string(k) + " ";
    if (l.direction != 0 && l.direction != 1)
      fail(name + "direction", l.direction, "0 (along d1) or 1 (along d2)");
    if (!(l.diameter > 0.0) || !std::isfinite(l.diameter))
      fail(name + "bar diameter", l.diameter, "> 0 m");
    if (!(l.spacing > l.diameter) || !std::isfinite(l.spacing))
      fail(name + "spacing", l.spacing,
           "> the bar diameter " + std::to_string(l.diameter) + " m (bars apart)");
    if (!std::isfinite(l.z) || std::abs(l.z) + 0.5 * l.diameter > 0.5 * thickness)
      fail(name + "height z", l.z,
           "such that |z| + d/2 <= h/2 = " + std::to_string(0.5 * thickness)
               + " m (the bars inside the shell's thickness)");
  }
}

ForceMethod parse_force_method(const std::string& s)
{
  if (s == "matmult")
    return ForceMethod::matmult;
  if (s == "residual")
    return ForceMethod::residual;
  throw std::runtime_error("internal-force method '" + s
                           + "': allowed are matmult, residual");
}

namespace
{
struct FormSet
{
  ufcx_form* a;
  ufcx_form* F;
  ufcx_form* m;
  ufcx_form* measure;
  ufcx_function_space* (*space)(const char*);
  bool shell;
  ufcx_form* sections = nullptr; ///< shells: the section's stresses (shell.py)
  ufcx_function_space* (*sections_space)(const char*) = nullptr;
};

FormSet forms_for(const dolfinx::mesh::Mesh& mesh)
{
  const auto ct = mesh.topology().cell_type();
  const int gdim = mesh.geometry().dim();
  using dolfinx::mesh::CellType;
  if (ct == CellType::triangle || ct == CellType::quadrilateral)
  {
    if (gdim != 3)
      throw std::runtime_error(
          "the shell needs a mesh of geometric dimension 3 (a mid-surface in "
          "space); this mesh has geometric dimension "
          + std::to_string(gdim) + ". Give 3D coordinates (x, y, z) to the nodes.");
    if (ct == CellType::triangle)
      return {form_shell_triangle_a, form_shell_triangle_F, form_shell_triangle_m_lumped, form_shell_triangle_measure,
              functionspace_form_shell_triangle_F, true, form_shell_triangle_sections,
              functionspace_form_shell_triangle_sections};
    return {form_shell_quadrilateral_a, form_shell_quadrilateral_F,
            form_shell_quadrilateral_m_lumped, form_shell_quadrilateral_measure, functionspace_form_shell_quadrilateral_F, true,
            form_shell_quadrilateral_sections, functionspace_form_shell_quadrilateral_sections};
  }
  if (ct == CellType::tetrahedron)
    return {form_solid_tetrahedron_a, form_solid_tetrahedron_F,
            form_solid_tetrahedron_m_lumped, form_solid_tetrahedron_measure, functionspace_form_solid_tetrahedron_F, false};
  if (ct == CellType::hexahedron)
    return {form_solid_hexahedron_a, form_solid_hexahedron_F,
            form_solid_hexahedron_m_lumped, form_solid_hexahedron_measure, functionspace_form_solid_hexahedron_F, false};
  throw std::runtime_error("unsupported cell type: shells take triangles or "
                           "quadrilaterals, solids tetrahedra or hexahedra");
}

void petsc_check(PetscErrorCode ierr, const char* what)
{
  if (ierr != 0)
    throw std::runtime_error(std::string("PETSc error in ") + what);
}

/// f = K u with K assembled once (PETSc BAIJ).
class MatMultForce final : public InternalForce
{
public:
  MatMultForce(std::shared_ptr<const Form<double>> a, int bs, std::size_t n)
      : _a(std::move(a))
  {
    _A = dolfinx::fem::petsc::create_matrix(*_a, "baij");
    petsc_check(VecCreateSeqWithArray(PETSC_COMM_SELF, bs, n, nullptr, &_x), "VecCreate");
    petsc_check(VecCreateSeqWithArray(PETSC_COMM_SELF, bs, n, nullptr, &_y), "VecCreate");
    update();
  }
  ~MatMultForce() override
  {
    VecDestroy(&_x);
    VecDestroy(&_y);
    MatDestroy(&_A);
  }
  void update() override
  {
    MatZeroEntries(_A);
    dolfinx::fem::assemble_matrix(
        dolfinx::la::petsc::Matrix::set_block_fn(_A, ADD_VALUES), *_a, {});
    MatAssemblyBegin(_A, MAT_FINAL_ASSEMBLY);
    MatAssemblyEnd(_A, MAT_FINAL_ASSEMBLY);
  }
  void apply(std::span<const double> u, std::span<double> f) override
  {
    VecPlaceArray(_x, u.data());
    VecPlaceArray(_y, f.data());
    MatMult(_A, _x, _y);
    VecResetArray(_x);
    VecResetArray(_y);
  }
  Mat matrix() const { return _A; }

private:
  std::shared_ptr<const Form<double>> _a;
  Mat _A = nullptr;
  Vec _x = nullptr, _y = nullptr;
};

/// f = F(u) assembled at every call (works for non-linear forms).
class ResidualForce final : public InternalForce
{
public:
  ResidualForce(std::shared_ptr<const Form<double>> F, std::shared_ptr<Function<double>> U)
      : _F(std::move(F)), _U(std::move(U))
  {
  }
  void update() override {}
  void apply(std::span<const double> u, std::span<double> f) override
  {
    auto x = _U->x()->mutable_array();
    std::copy(u.begin(), u.end(), x.begin());
    std::fill(f.begin(), f.end(), 0.0);
    dolfinx::fem::assemble_vector(f, *_F);
  }

private:
  std::shared_ptr<const Form<double>> _F;
  std::shared_ptr<Function<double>> _U;
};
} // namespace

struct FEModel::Impl
{
  Material mat;
  ForceMethod method;
  bool shell = true;
  int bs = 6;
  std::shared_ptr<dolfinx::mesh::Mesh> mesh;
  std::shared_ptr<FunctionSpace> V, W;
  std::shared_ptr<Function<double>> eta, U, steel;
  std::map<std::string, std::shared_ptr<const Constant<double>>> constants;
  std::shared_ptr<Form<double>> a, F, m, measure, sections;
  std::unique_ptr<InternalForce> force;
  std::vector<double> x;             // (nodes, 3)
  std::vector<std::int32_t> cells;   // (cells, npc)
  int npc = 0;
  std::vector<std::int32_t> v_to_w;  // node -> W dof
  std::vector<double> normals, weight;
  std::vector<std::int32_t> spring_dofs; // set_support_springs
  std::vector<double> spring_k;

  /// f = K u (the form) plus the springs: compression-only, or two-sided
  /// for the step's bound.
  void force_with_springs(std::span<const double> u, std::span<double> f, bool two_sided) const
  {
    force->apply(u, f);
    for (std::size_t q = 0; q < spring_dofs.size(); ++q)
    {
      const double uq = u[spring_dofs[q]];
      f[spring_dofs[q]] += spring_k[q] * (two_sided ? uq : std::min(uq, 0.0));
    }
  }
};

FEModel::FEModel(std::shared_ptr<dolfinx::mesh::Mesh> mesh, const Material& material,
                 ForceMethod method)
    : _impl(std::make_unique<Impl>())
{
  auto& I = *_impl;
  if (!mesh)
    throw std::runtime_error("FEModel: no mesh given");
  if (dolfinx::MPI::size(mesh->comm()) != 1)
    throw std::runtime_error("FEModel runs on one MPI rank for now");
  const FormSet fs = forms_for(*mesh);
  validate(material, fs.shell);
  I.mat = material;
  I.method = method;
  I.shell = fs.shell;
  I.bs = fs.shell ? 6 : 3;
  I.mesh = mesh;
  I.V = std::make_shared<FunctionSpace>(dolfinx::fem::create_functionspace(fs.space, "U", mesh));
  I.W = std::make_shared<FunctionSpace>(dolfinx::fem::create_functionspace(fs.space, "eta", mesh));
  I.eta = std::make_shared<Function<double>>(I.W);
  I.U = std::make_shared<Function<double>>(I.V);
  std::fill(I.eta->x()->mutable_array().begin(), I.eta->x()->mutable_array().end(), 1.0);

  auto constant = [](double v) { return std::make_shared<const Constant<double>>(v); };
  I.constants = {{"E", constant(material.youngs_modulus)}, {"nu", constant(material.poisson_ratio)},
                 {"rho", constant(material.density)}};
  if (fs.shell)
  {
    I.constants["h"] = constant(material.thickness);
    I.constants["k_shear"] = constant(material.shear_factor);
    I.constants["c_drill"] = constant(material.drilling);
  }
  std::map<std::string, std::shared_ptr<const Function<double>>> a_coeffs{{"eta", I.eta}},
      F_coeffs{{"eta", I.eta}, {"U", I.U}}, m_coeffs;
  if (fs.shell)
  {
    // the smeared reinforcement, zero (plain concrete) until set
    I.steel = std::make_shared<Function<double>>(std::make_shared<FunctionSpace>(
        dolfinx::fem::create_functionspace(fs.space, "steel", mesh)));
    a_coeffs["steel"] = F_coeffs["steel"] = m_coeffs["steel"] = I.steel;
  }
  I.a = std::make_shared<Form<double>>(
      dolfinx::fem::create_form<double>(*fs.a, {I.V, I.V}, a_coeffs, I.constants, {}));
  I.F = std::make_shared<Form<double>>(
      dolfinx::fem::create_form<double>(*fs.F, {I.V}, F_coeffs, I.constants, {}));
  I.m = std::make_shared<Form<double>>(
      dolfinx::fem::create_form<double>(*fs.m, {I.V}, m_coeffs, I.constants, {}));
  I.measure = std::make_shared<Form<double>>(
      dolfinx::fem::create_form<double>(
          *fs.measure, {I.V}, std::map<std::string, std::shared_ptr<const Function<double>>>{},
          std::map<std::string, std::shared_ptr<const Constant<double>>>{}, {}));
  if (fs.sections)
  {
    auto Q = std::make_shared<FunctionSpace>(dolfinx::fem::create_functionspace(fs.sections_space, "q", mesh));
    const std::map<std::string, std::shared_ptr<const Constant<double>>> c{
        {"E", I.constants["E"]}, {"nu", I.constants["nu"]}, {"h", I.constants["h"]}};
    I.sections = std::make_shared<Form<double>>(
        dolfinx::fem::create_form<double>(*fs.sections, {Q}, {{"U", I.U}}, c, {}));
  }

  // Nodes, cells, node -> weight-space map.
  const auto dm = I.V->dofmap();
  const std::size_t nn = dm->index_map->size_local() + dm->index_map->num_ghosts();
  I.x = I.V->tabulate_dof_coordinates(false);
  I.x.resize(3 * nn);
  const auto& list = dm->list();
  I.npc = static_cast<int>(list.links(0).size());
  I.cells.assign(list.array().begin(), list.array().end());
  I.v_to_w.assign(nn, -1);
  const auto& wlist = I.W->dofmap()->list();
  for (std::int32_t c = 0; c < list.num_nodes(); ++c)
  {
    auto vd = list.links(c);
    auto wd = wlist.links(c);
    for (std::size_t k = 0; k < vd.size(); ++k)
      I.v_to_w[vd[k]] = wd[k];
  }
  I.weight.assign(nn, 1.0);

  if (I.shell)
  {
    I.normals.assign(3 * nn, 0.0);
    std::vector<int> count(nn, 0);
    for (std::size_t c = 0; c < num_cells(); ++c)
    {
      const std::int32_t* v = &I.cells[c * I.npc];
      std::array<double, 3> e1, e2;
      for (int i = 0; i < 3; ++i)
      {
        e1[i] = I.x[3 * v[1] + i] - I.x[3 * v[0] + i];
        e2[i] = I.x[3 * v[2] + i] - I.x[3 * v[0] + i];
      }
      std::array<double, 3> n = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                 e1[0] * e2[1] - e1[1] * e2[0]};
      const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (!(len > 0.0))
        throw std::runtime_error("shell cell " + std::to_string(c) + " is degenerate (zero area)");
      for (int k = 0; k < I.npc; ++k)
      {
        for (int i = 0; i < 3; ++i)
          I.normals[3 * v[k] + i] += n[i] / len;
        ++count[v[k]];
      }
    }
    for (std::size_t i = 0; i < nn; ++i)
    {
      double* n = &I.normals[3 * i];
      const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      if (!(len > 1e-6 * count[i]))
        throw std::runtime_error(
            "the cells around shell node " + std::to_string(i)
            + " have opposite normals: orient the mesh cells consistently");
      for (int k = 0; k < 3; ++k)
        n[k] /= len;
    }
  }

  if (method == ForceMethod::matmult)
    I.force = std::make_unique<MatMultForce>(I.a, I.bs, nn * I.bs);
  else
    I.force = std::make_unique<ResidualForce>(I.F, I.U);
}

FEModel::~FEModel() = default;
FEModel::FEModel(FEModel&&) noexcept = default;
FEModel& FEModel::operator=(FEModel&&) noexcept = default;

bool FEModel::is_shell() const { return _impl->shell; }
int FEModel::block_size() const { return _impl->bs; }
std::size_t FEModel::num_nodes() const { return _impl->x.size() / 3; }
std::size_t FEModel::num_dofs() const { return num_nodes() * _impl->bs; }
const Material& FEModel::material() const { return _impl->mat; }
std::span<const double> FEModel::node_coordinates() const { return _impl->x; }
std::span<const std::int32_t> FEModel::cell_nodes() const { return _impl->cells; }
int FEModel::nodes_per_cell() const { return _impl->npc; }
std::size_t FEModel::num_cells() const { return _impl->cells.size() / _impl->npc; }
std::shared_ptr<const FunctionSpace> FEModel::function_space() const { return _impl->V; }
std::shared_ptr<dolfinx::mesh::Mesh> FEModel::mesh() const { return _impl->mesh; }

NodalLoad FEModel::pressure_load(const std::string& name,
                                 std::span<const std::int32_t> nodes, History p) const
{
  if (!_impl->shell)
    throw std::runtime_error("pressure load '" + name + "': only for shell models");
  if (nodes.empty())
    throw std::runtime_error("pressure load '" + name + "' has no node");
  const auto area = nodal_measure();
  NodalLoad load{name, {}, {}, std::move(p)};
  for (auto n : nodes)
    for (int i = 0; i < 3; ++i)
    {
      load.dofs.push_back(n * 6 + i);
      load.weights.push_back(area[n] * _impl->normals[3 * n + i]);
    }
  return load;
}

Mat FEModel::stiffness_matrix() const
{
  auto* mm = dynamic_cast<MatMultForce*>(_impl->force.get());
  return mm ? mm->matrix() : nullptr;
}

std::span<const double> FEModel::nodal_normals() const
{
  if (!_impl->shell)
    throw std::runtime_error("nodal normals exist only for shell models");
  return _impl->normals;
}

std::vector<double> FEModel::lumped_mass() const
{
  std::vector<double> m(num_dofs(), 0.0);
  dolfinx::fem::assemble_vector(std::span<double>(m), *_impl->m);
  return m;
}

std::vector<double> FEModel::section_stresses(std::span<const double> u) const
{
  auto& I = *_impl;
  if (!I.sections)
    throw std::runtime_error("section stresses exist only for shell models");
  if (u.size() != num_dofs())
    throw std::runtime_error("section stresses: " + std::to_string(u.size()) + " dof values for a model of "
                             + std::to_string(num_dofs()));
  std::copy(u.begin(), u.end(), I.U->x()->mutable_array().begin());
  const auto Q = I.sections->function_spaces()[0];
  const int bs = Q->dofmap()->bs(); // 37: 36 values and the cell's area
  const auto im = Q->dofmap()->index_map;
  std::vector<double> b((im->size_local() + im->num_ghosts()) * bs, 0.0);
  dolfinx::fem::assemble_vector(std::span<double>(b), *I.sections);
  const std::size_t nc = num_cells();
  std::vector<double> out(36 * nc);
  for (std::size_t c = 0; c < nc; ++c)
  {
    const double* v = &b[bs * Q->dofmap()->cell_dofs(static_cast<std::int32_t>(c))[0]];
    for (int k = 0; k < 36; ++k)
      out[36 * c + k] = v[k] / v[36];
  }
  return out;
}

std::vector<double> FEModel::nodal_measure() const
{
  std::vector<double> m(num_dofs(), 0.0);
  dolfinx::fem::assemble_vector(std::span<double>(m), *_impl->measure);
  std::vector<double> a(num_nodes());
  for (std::size_t i = 0; i < a.size(); ++i)
    a[i] = m[i * _impl->bs];
  return a;
}

void FEModel::set_weight(std::span<const double> eta)
{
  auto& I = *_impl;
  if (eta.size() != num_nodes())
    throw std::runtime_error("energy weight: " + std::to_string(eta.size())
                             + " values given for " + std::to_string(num_nodes()) + " nodes");
  auto w = I.eta->x()->mutable_array();
  for (std::size_t i = 0; i < eta.size(); ++i)
  {
    if (!(eta[i] >= 0.0 && eta[i] <= 1.0))
      throw std::runtime_error("energy weight " + std::to_string(eta[i]) + " at node "
                               + std::to_string(i) + ": must be in [0, 1]");
    w[I.v_to_w[i]] = eta[i];
  }
  I.weight.assign(eta.begin(), eta.end());
  I.force->update();
}

std::span<const double> FEModel::weight() const { return _impl->weight; }

void FEModel::set_reinforcement(const Reinforcement& r, std::span<const std::int32_t> cells)
{
  auto& I = *_impl;
  if (!I.shell)
    throw std::runtime_error("reinforcement: only shell models take a layered section");
  validate(r, I.mat.thickness);
  std::vector<std::int32_t> all;
  if (cells.empty())
  {
    all.resize(num_cells());
    std::iota(all.begin(), all.end(), 0);
    cells = all;
  }
  const auto sums = section_sums(r);
  const double de = r.youngs_modulus - I.mat.youngs_modulus;
  const double dr = r.density - I.mat.density;
  std::array<double, 11> values{
      de * sums[0][0], de * sums[0][1], de * sums[0][2], de * sums[1][0], de * sums[1][1],
      de * sums[1][2], dr * (sums[0][0] + sums[1][0]), dr * (sums[0][2] + sums[1][2]),
      0.0, 0.0, 0.0};
  const auto& dofs = I.steel->function_space()->dofmap()->list();
  const int bs = I.steel->function_space()->dofmap()->bs();
  auto x = I.steel->x()->mutable_array();
  const double len = std::sqrt(r.direction[0] * r.direction[0] + r.direction[1] * r.direction[1]
                               + r.direction[2] * r.direction[2]);
  for (int k = 0; k < 3; ++k)
    values[8 + k] = r.layers.empty() ? 0.0 : r.direction[k] / len;
  // every cell checked before any is written (an error leaves the model as it was)
  for (std::int32_t c : cells)
  {
    if (c < 0 || static_cast<std::size_t>(c) >= num_cells())
      throw std::runtime_error("reinforcement: cell " + std::to_string(c) + " out of range (the mesh has "
                               + std::to_string(num_cells()) + " cells)");
    // the cell's normal, as the form builds it (first two edges from vertex 0)
    const std::int32_t* v = &I.cells[c * I.npc];
    std::array<double, 3> e1, e2;
    for (int i = 0; i < 3; ++i)
    {
      e1[i] = I.x[3 * v[1] + i] - I.x[3 * v[0] + i];
      e2[i] = I.x[3 * v[2] + i] - I.x[3 * v[0] + i];
    }
    std::array<double, 3> n{e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                            e1[0] * e2[1] - e1[1] * e2[0]};
    const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    const double dn = (n[0] * r.direction[0] + n[1] * r.direction[1] + n[2] * r.direction[2]) / (nl * len);
    if (!(std::abs(dn) < 0.999))
      throw std::runtime_error("reinforcement: the bar direction is (nearly) normal to cell "
                               + std::to_string(c) + ": its projection on the cell's plane "
                                                     "fixes d1, give a vector along the shell");
  }
  for (std::int32_t c : cells)
  {
    const std::int32_t dof = dofs.links(c)[0];
    for (int k = 0; k < 11; ++k)
      x[dof * bs + k] = values[k];
  }
  I.force->update();
}

void FEModel::set_support_springs(std::vector<std::int32_t> dofs, std::vector<double> k)
{
  if (dofs.size() != k.size())
    throw std::runtime_error("support springs: " + std::to_string(dofs.size()) + " dofs but "
                             + std::to_string(k.size()) + " stiffnesses");
  for (std::size_t q = 0; q < dofs.size(); ++q)
  {
    if (dofs[q] < 0 || static_cast<std::size_t>(dofs[q]) >= num_dofs())
      throw std::runtime_error("support springs: dof " + std::to_string(dofs[q]) + " outside [0, "
                               + std::to_string(num_dofs()) + ")");
    if (!(k[q] > 0.0) || !std::isfinite(k[q]))
      throw std::runtime_error("support springs: stiffness " + std::to_string(k[q]) + " N/m of dof "
                               + std::to_string(dofs[q]) + ": must be > 0");
  }
  _impl->spring_dofs = std::move(dofs);
  _impl->spring_k = std::move(k);
}

std::span<const std::int32_t> FEModel::support_spring_dofs() const { return _impl->spring_dofs; }

double FEModel::support_spring_force(std::span<const double> u) const
{
  const auto& I = *_impl;
  double f = 0.0;
  for (std::size_t q = 0; q < I.spring_dofs.size(); ++q)
    f -= I.spring_k[q] * std::min(u[I.spring_dofs[q]], 0.0);
  return f;
}

void FEModel::internal_force(std::span<const double> u, std::span<double> f) const
{
  _impl->force_with_springs(u, f, false);
}

InternalForceFn FEModel::internal_force_fn() const
{
  const Impl* I = _impl.get();
  return [I](std::span<const double> u, std::span<double> f) { I->force_with_springs(u, f, false); };
}

InternalForceFn FEModel::bounding_force_fn() const
{
  const Impl* I = _impl.get();
  return [I](std::span<const double> u, std::span<double> f) { I->force_with_springs(u, f, true); };
}

double FEModel::critical_time_step(std::span<const double> mass) const
{
  if (mass.size() != num_dofs())
    throw std::runtime_error("critical_time_step: mass size differs from the dofs");
  const double lmax = core::max_eigenvalue(mass, bounding_force_fn());
  return 2.0 / std::sqrt(lmax);
}

std::vector<std::vector<std::int32_t>> FEModel::boundary_facets() const
{
  auto& I = *_impl;
  auto& topo = I.mesh->topology_mutable();
  const int tdim = topo.dim(), fdim = tdim - 1;
  topo.create_entities(fdim);
  topo.create_connectivity(fdim, tdim);
  topo.create_connectivity(tdim, fdim);
  const auto f_to_c = topo.connectivity(fdim, tdim);
  const auto c_to_f = topo.connectivity(tdim, fdim);
  const auto& layout = I.V->dofmap()->element_dof_layout();
  std::vector<std::vector<std::int32_t>> facets;
  for (std::int32_t f : dolfinx::mesh::exterior_facet_indices(topo))
  {
    const std::int32_t c = f_to_c->links(f)[0];
    const auto cf = c_to_f->links(c);
    const int lf = static_cast<int>(std::find(cf.begin(), cf.end(), f) - cf.begin());
    std::vector<std::int32_t> fn;
    for (int k : layout.entity_closure_dofs(fdim, lf))
      fn.push_back(I.cells[c * I.npc + k]);
    facets.push_back(std::move(fn));
  }
  return facets;
}

std::vector<std::int32_t> FEModel::boundary_nodes() const
{
  std::vector<std::int32_t> nodes;
  for (const auto& fn : boundary_facets())
    nodes.insert(nodes.end(), fn.begin(), fn.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

std::vector<double> FEModel::boundary_load_weights(std::span<const std::int32_t> nodes) const
{
  auto& I = *_impl;
  const int tdim = I.mesh->topology().dim();
  std::set<std::int32_t> selected(nodes.begin(), nodes.end());
  std::vector<double> w(nodes.size(), 0.0);
  std::map<std::int32_t, std::size_t> pos;
  for (std::size_t k = 0; k < nodes.size(); ++k)
    pos[nodes[k]] = k;
  for (const auto& fn : boundary_facets())
  {
    if (!std::all_of(fn.begin(), fn.end(), [&](auto n) { return selected.count(n) > 0; }))
      continue;
    auto p = [&](int k, int i) { return I.x[3 * fn[k] + i]; };
    double measure = 0.0;
    if (fn.size() == 2)
      measure = std::sqrt(std::pow(p(1, 0) - p(0, 0), 2) + std::pow(p(1, 1) - p(0, 1), 2)
                          + std::pow(p(1, 2) - p(0, 2), 2));
    else
    {
      // triangle (0,1,2) or tensor-ordered quadrilateral (diagonals 0-3, 1-2)
      std::array<double, 3> d1, d2;
      const bool quad = fn.size() == 4;
      for (int i = 0; i < 3; ++i)
      {
        d1[i] = quad ? p(3, i) - p(0, i) : p(1, i) - p(0, i);
        d2[i] = quad ? p(2, i) - p(1, i) : p(2, i) - p(0, i);
      }
      measure = 0.5 * std::sqrt(std::pow(d1[1] * d2[2] - d1[2] * d2[1], 2)
                                + std::pow(d1[2] * d2[0] - d1[0] * d2[2], 2)
                                + std::pow(d1[0] * d2[1] - d1[1] * d2[0], 2));
    }
    for (auto n : fn)
      w[pos[n]] += measure / fn.size();
  }
  double total = 0.0;
  for (double v : w)
    total += v;
  if (!(total > 0.0))
    throw std::runtime_error("the selected nodes span no boundary "
                             + std::string(tdim == 2 ? "edge" : "face")
                             + ": a distributed load needs a boundary region");
  for (double& v : w)
    v /= total;
  return w;
}

namespace
{
/// LU factorisation of K with the fixed dofs' rows and columns replaced by
/// the identity (MUMPS).
class DirectSolver
{
public:
  DirectSolver(const Form<double>& a, int bs, std::size_t n,
               std::span<const std::int32_t> fixed)
      : _n(n), _fixed(fixed.begin(), fixed.end())
  {
    _K = dolfinx::fem::petsc::create_matrix(a, "baij");
    MatZeroEntries(_K);
    dolfinx::fem::assemble_matrix(dolfinx::la::petsc::Matrix::set_block_fn(_K, ADD_VALUES), a,
                                  {});
    MatAssemblyBegin(_K, MAT_FINAL_ASSEMBLY);
    MatAssemblyEnd(_K, MAT_FINAL_ASSEMBLY);
    std::vector<PetscInt> rows(fixed.begin(), fixed.end());
    MatZeroRowsColumns(_K, rows.size(), rows.data(), 1.0, nullptr, nullptr);
    VecCreateSeqWithArray(PETSC_COMM_SELF, bs, n, nullptr, &_b);
    VecCreateSeqWithArray(PETSC_COMM_SELF, bs, n, nullptr, &_x);
    KSPCreate(PETSC_COMM_SELF, &_ksp);
    KSPSetOperators(_ksp, _K, _K);
    KSPSetType(_ksp, KSPPREONLY);
    PC pc;
    KSPGetPC(_ksp, &pc);
    PCSetType(pc, PCLU);
    PCFactorSetMatSolverType(pc, MATSOLVERMUMPS);
    KSPSetUp(_ksp);
  }
  ~DirectSolver()
  {
    KSPDestroy(&_ksp);
    VecDestroy(&_b);
    VecDestroy(&_x);
    MatDestroy(&_K);
  }
  /// x = K^-1 b with b zeroed on the fixed dofs.
  void solve(std::vector<double> b, std::span<double> x)
  {
    for (auto d : _fixed)
      b[d] = 0.0;
    VecPlaceArray(_b, b.data());
    VecPlaceArray(_x, x.data());
    KSPSolve(_ksp, _b, _x);
    VecResetArray(_b);
    VecResetArray(_x);
    KSPConvergedReason reason;
    KSPGetConvergedReason(_ksp, &reason);
    if (reason < 0)
      throw std::runtime_error("direct solve failed (PETSc reason " + std::to_string(reason)
                               + "): is the structure held against rigid motions?");
  }

private:
  std::size_t _n;
  std::vector<std::int32_t> _fixed;
  Mat _K = nullptr;
  Vec _b = nullptr, _x = nullptr;
  KSP _ksp = nullptr;
};
} // namespace

std::vector<double> FEModel::solve_static(std::span<const double> f,
                                          std::span<const std::int32_t> fixed_dofs) const
{
  const std::size_t n = num_dofs();
  if (f.size() != n)
    throw std::runtime_error("solve_static: load vector size differs from the dofs");
  DirectSolver solver(*_impl->a, _impl->bs, n, fixed_dofs);
  std::vector<double> u(n, 0.0);
  solver.solve(std::vector<double>(f.begin(), f.end()), u);
  return u;
}

std::pair<std::vector<double>, double>
FEModel::lowest_mode(std::span<const double> mass, std::span<const std::int32_t> fixed_dofs,
                     std::span<const double> x0, int iterations) const
{
  const std::size_t n = num_dofs();
  if (mass.size() != n || x0.size() != n)
    throw std::runtime_error("lowest_mode: mass or start vector size differs from the dofs");
  DirectSolver solver(*_impl->a, _impl->bs, n, fixed_dofs);
  std::vector<double> x(x0.begin(), x0.end()), b(n), kx(n);
  for (int it = 0; it < iterations; ++it)
  {
    for (std::size_t i = 0; i < n; ++i)
      b[i] = mass[i] * x[i];
    solver.solve(b, x);
    double norm = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      norm += mass[i] * x[i] * x[i];
    norm = std::sqrt(norm);
    for (double& v : x)
      v /= norm;
  }
  internal_force(x, kx);
  double xkx = 0.0, xmx = 0.0;
  for (std::size_t i = 0; i < n; ++i)
  {
    xkx += x[i] * kx[i];
    xmx += mass[i] * x[i] * x[i];
  }
  return {x, xkx / xmx};
}

} // namespace dembridge::shell
