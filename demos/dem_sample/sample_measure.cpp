// The measurements of a sample test (sample_run.h): the curves' points,
// the peak and the stop criteria, the moduli, the summary, where the links
// broke.
#include "sample_run.h"

namespace dembridge::demo::sample_detail
{

void SampleRun::measure(bool print, bool frame)
{
  const double H = _cfg.height;
  const double strain = (mean_uz(_top) - mean_uz(_bottom)) / H;
  // the stress averaged over the gauge: damping (c m v) and inertia load
  // the sample in proportion to the velocity and acceleration, both
  // linear in z, so the axial stress grows as z^2 from the bottom platen
  // to the top one, and its mean over [H/4, 3H/4] is s_bot + 13/48 (s_top
  // - s_bot). The top platen's stress alone makes E and sigma_t depend on
  // the loading rate (by ~2 % when it is halved).
  const double f_top = _solver->reaction("top")[2], s_bot = -_solver->reaction("bottom")[2] / _area;
  const double stress = axial_stress();
  const double confining = _lateral; // as applied over the last step (0 but in a triaxial test)
  double ul = 0.0;
  for (std::size_t g = 0; g < _gauge.size(); ++g)
    for (int k = 0; k < 3; ++k)
      ul += (_p.x[3 * _gauge[g] + k] - _p.x0[3 * _gauge[g] + k]) * _gauge_dir[g][k];
  const double lateral = ul / _gauge.size() / _half_width;
  const double axial = (mean_z(_g_hi, _p.x) - mean_z(_g_lo, _p.x)) / _gauge_length - 1.0;
  _eps.push_back(strain);
  _ax.push_back(axial);
  _sig.push_back(stress);
  _lat.push_back(lateral);
  _conf.push_back(confining);
  track_peak(strain, stress, confining, s_bot);
  if (_csv.is_open() || print)
    write_point(print, strain, stress, lateral, axial, f_top, confining);
  if (frame && _writer)
    _writer->write(_solver->time(), _p, _links);
}

void SampleRun::track_peak(double strain, double stress, double confining, double s_bot)
{
  const double tracked = std::abs(stress) - confining;
  // (a triaxial test's deviator counts from the held confinement on: in
  // the hydrostatic phase it is the last step's lag alone)
  if (_cfg.test == "triaxial" && !_confined)
    return;
  if (tracked > _peak)
  {
    _peak = tracked;
    _axial_at_peak = stress;
    _lateral_at_peak = confining;
    _eps_peak = std::abs(strain);
    const auto e = _solver->energy();
    _dissipated_at_peak = e.softening + e.breakage;
    _demand_at_peak = _solver->cohesion_demand();
  }
  else if (_cfg.to_separation)
  {
    // separated: the force through the crack, which the bottom platen
    // carries (the top one also pulls the top part through the damping,
    // c m v), stays below 1 % of the peak for two periods of the first
    // axial mode (4H/c each), so that no snap-back oscillation passing
    // through zero counts. (Intact links may still join the two parts:
    // chains of links that rotate with their spheres carry almost no
    // force.) Afterwards the links can dissipate at most 1 % of the peak
    // force times the further opening.
    if (std::abs(s_bot) < 0.01 * _peak)
    {
      if (_t_low < 0.0)
        _t_low = _solver->time();
      if (_solver->time() - _t_low >= 8.0 * _cfg.height / _c_wave)
        _after_peak = _separated = true;
    }
    else
      _t_low = -1.0;
  }
  else if (_peak > 0.0 && tracked < _cfg.stop_ratio * _peak)
    _after_peak = true;
}

void SampleRun::measure_moduli()
{
  if (_cfg.test == "triaxial")
  {
    measure_triaxial_moduli();
    return;
  }
  std::vector<double> e1, s1, l1, ep;
  for (std::size_t i = 0; i < _eps.size(); ++i)
  {
    if (std::abs(_eps[i]) > _eps_peak)
      break;
    if (std::abs(_sig[i]) >= 0.05 * _peak && std::abs(_sig[i]) <= 0.3 * _peak)
    {
      e1.push_back(_ax[i]);
      ep.push_back(_eps[i]);
      s1.push_back(_sig[i]);
      l1.push_back(_lat[i]);
    }
  }
  const double E = e1.size() >= 3 ? slope(e1, s1) : 0.0;
  const double nu = e1.size() >= 3 ? -slope(e1, l1) : 0.0;
  _out["youngs_modulus_pa"] = E;
  _out["gauge_length_m"] = _gauge_length;
  _out["platen_modulus_pa"] = e1.size() >= 3 ? slope(ep, s1) : 0.0; // for comparison
  _out["poisson_ratio"] = nu;
}

void SampleRun::measure_triaxial_moduli()
{
  std::vector<double> ev, pm, ea, q, el;
  const double P = _cfg.confinement;
  for (std::size_t i = 0; i < _eps.size(); ++i)
  {
    if (_conf[i] >= 0.1 * P && _conf[i] <= 0.5 * P)
    {
      ev.push_back(-(_ax[i] + 2.0 * _lat[i]));
      pm.push_back((std::abs(_sig[i]) + 2.0 * _conf[i]) / 3.0);
    }
    const double d = std::abs(_sig[i]) - _conf[i];
    if (std::abs(_eps[i]) > _eps_peak)
      break;
    if (_conf[i] == P && d >= 0.05 * _peak && d <= 0.3 * _peak)
    {
      ea.push_back(_ax[i]);
      q.push_back(-d);
      el.push_back(_lat[i]);
    }
  }
  _out["bulk_modulus_pa"] = ev.size() >= 3 ? slope(ev, pm) : 0.0;
  _out["youngs_modulus_pa"] = ea.size() >= 3 ? slope(ea, q) : 0.0;
  _out["poisson_ratio"] = ea.size() >= 3 ? -slope(ea, el) : 0.0;
}

void SampleRun::report()
{
  if (_cfg.test == "triaxial")
  {
    // the deviator's peak, with the stresses then (compression > 0)
    _out["confinement_pa"] = _cfg.confinement;
    _out["peak_deviator_pa"] = _peak;
    _out["axial_stress_at_peak_pa"] = std::abs(_axial_at_peak);
    _out["lateral_stress_at_peak_pa"] = _lateral_at_peak;
    _out["mean_stress_at_peak_pa"] = (std::abs(_axial_at_peak) + 2.0 * _lateral_at_peak) / 3.0;
    _out["final_deviator_pa"] = std::abs(_sig.back()) - _conf.back();
    _out["final_lateral_strain"] = _lat.back();
    _out["final_gauge_strain"] = _ax.back();
  }
  _out["peak_stress_pa"] = _cfg.test == "triaxial" ? std::abs(_axial_at_peak) : _peak;
  _out["strain_at_peak"] = _eps_peak;
  _out["final_strain"] = _eps.back();
  _out["links_broken_tension"] = _links.count(LinkState::broken_tension);
  _out["links_broken_shear"] = _links.count(LinkState::broken_shear);
  _out["cohesion_demand_pa"] = _solver->cohesion_demand();
  _out["cohesion_demand_at_peak_pa"] = _demand_at_peak;
  const auto e = _solver->energy();
  _out["energy"] = {{"kinetic_j", e.kinetic},       {"elastic_j", e.elastic},
                    {"softening_j", e.softening},   {"breakage_j", e.breakage},
                    {"friction_j", e.friction},     {"damping_j", e.damping},
                    {"work_j", e.external_work + e.prescribed_work}, {"imbalance_j", e.imbalance()}};
  // Fracture energy: what the links dissipate (softening and the energy
  // left in a link when it breaks) per unit of cross-section, once the
  // sample is separated (to_separation: the force through the crack below
  // 1 % of the peak). The platen's work also pays the damping of the
  // snap-back (the elastic energy the sample releases faster than the
  // crack absorbs it, which a laboratory's closed-loop test avoids), so it
  // is reported apart, not counted.
  crack_location();
  _out["separated"] = _separated;
  _out["dissipated_links_j"] = e.softening + e.breakage;
  _out["dissipated_before_peak_j"] = _dissipated_at_peak;
  _out["fracture_energy_j_m2"] = (e.softening + e.breakage) / _area;
  _out["work_per_area_j_m2"] = (e.external_work + e.prescribed_work) / _area;
  _out["cross_section_m2"] = _area;
  _out["steps"] = _solver->steps();
  _out["reached_peak"] = _after_peak;
  _out["wall_s"] = _clock.seconds();
  if (_writer)
    _out["frames"] = _writer->frames();
}

void SampleRun::crack_location()
{
  const double H = _cfg.height, band = 2.0 * _rmax;
  std::vector<double> z;
  std::size_t near = 0;
  for (std::size_t k = 0; k < _links.size(); ++k)
  {
    if (_links.state[k] == LinkState::intact)
      continue;
    const double zm = 0.5 * (_p.x0[3 * _links.a[k] + 2] + _p.x0[3 * _links.b[k] + 2]);
    z.push_back(zm);
    near += zm < band || zm > H - band;
  }
  _out["links_broken_near_platens"] = near;
  if (z.empty())
    _out["crack_height_m"] = nullptr;
  else
  {
    std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
    _out["crack_height_m"] = z[z.size() / 2];
  }
}

} // namespace dembridge::demo::sample_detail
