// Checkpoint and restart of the explicit shell solver: its state written to
// a checkpoint group and read back bit for bit (checkpoint.h).
#include "dembridge/shell/explicit.h"

#include <stdexcept>

namespace dembridge::shell
{
using checkpoint::Group;

namespace
{
std::string motion_names(const std::vector<PrescribedMotion>& motions)
{
  std::string s;
  for (const auto& m : motions)
    s += m.name + '\n';
  return s;
}
} // namespace

void ExplicitSolver::save(const Group& g) const
{
  if (_in_step)
    throw std::runtime_error("ExplicitSolver::save between begin_step and end_step: save at the end of a step");
  for (auto [name, v] : {std::pair{"mass", &_m}, {"u", &_u}, {"v", &_v}, {"a", &_a}, {"f_int", &_fint},
                         {"f_ext", &_fext}, {"f_ext_new", &_fext_new}, {"reactions", &_r}, {"v_old", &_v_old}})
    g.write(name, *v);
  g.write("time", _t);
  g.write_int("steps", _steps);
  g.write("dt", _dt);
  g.write("damping", _c);
  g.write("energy", std::vector<double>{_e.initial, _e.kinetic, _e.strain, _e.external_work,
                                        _e.prescribed_work, _e.damping});
  g.write("motions", motion_names(_motions));
}

void ExplicitSolver::load(const Group& g)
{
  if (_in_step)
    throw std::runtime_error("ExplicitSolver::load between begin_step and end_step");
  if (g.read_double("dt") != _dt)
    g.fail("dt", "the time step " + std::to_string(g.read_double("dt")) + " s differs from this run's "
                     + std::to_string(_dt) + " s");
  if (g.read_string("motions") != motion_names(_motions))
    g.fail("motions", "the prescribed motions differ from this run's (another set-up, or a motion "
                      "released: load the state once the run's motions are those of the checkpoint)");
  std::vector<double> m;
  g.read("mass", m);
  if (m != _m)
    g.fail("mass", "the lumped masses differ from this run's (another mesh, material or weighting)");
  for (auto [name, v] : {std::pair{"u", &_u}, {"v", &_v}, {"a", &_a}, {"f_int", &_fint}, {"f_ext", &_fext},
                         {"f_ext_new", &_fext_new}, {"reactions", &_r}, {"v_old", &_v_old}})
    g.read_exact(name, *v);
  _t = g.read_double("time");
  _steps = g.read_int("steps");
  _c = g.read_double("damping");
  std::vector<double> e;
  g.read("energy", e);
  if (e.size() != 6)
    g.fail("energy", "unexpected length (file damaged?)");
  _e = {e[0], e[1], e[2], e[3], e[4], e[5]};
}

} // namespace dembridge::shell
