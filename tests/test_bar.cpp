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
    double errs[3];
    int m = 0;
    for (const std::string model : {"fe", "coupled", "de"})
    {
      auto c = reduced(model, load, "static");
      c.fe_youngs_modulus = E;
      const auto r = demo::run_bar(c);
      const double err = r.at("static_relative_error").get<double>();
      errs[m++] = err;
      INFO(model << " " << load << ": end displacement " << r.at("static_end_displacement_m")
                 << " m, beam theory " << r.at("reference_end_displacement_m") << " m, error " << err);
      // Beam theory over the span from the support to the load (for a set of
      // spheres: the mean x of their centres), the end loaded through a
      // rigid plate (hinged at its centroid in bending). FE: the 2 % (measured
      // -0.2 % tension, -0.6 % bending: the clamp holds the Poisson
      // contraction).
      // Spheres: the layer at each face lies flat on it with ~7 links per
      // sphere against 12 in the bulk: a skin about one radius deep with
      // ~7/12 of the bulk's stiffness (model below, measured profile in
      // README). E was measured in tension on the middle half, so it holds
      // the skins of the four long faces but not those of the end faces,
      // and not the z^2 weight bending gives the top and bottom skins.
      const double sk = 7.0 / 12.0, t = c.mean_radius / c.width; // skin stiffness share, depth / side
      const double span = r.at("beam_span_m").get<double>();
      const double end_skin = (1.0 / sk - 1.0) * c.mean_radius / span; // one end face's skin, per span
      // tension: the end skins (one at the DE bar's support, one at each
      // loaded end) add end_skin each; a margin of 2 % for E, which scatters
      // by ~2 % between packings (the coupled bar has its own). Measured DE
      // +3.3 % (estimate 3.5 %), coupled +0.7 % (1.7 %).
      const double ends = model == "de" ? 2.0 : 1.0;
      const double est_tension = ends * end_skin;
      // bending: compliance over what the tension E predicts, A_eff / A over
      // I_eff / I with the skin on all four long faces (the bending part,
      // ~94 % of the deflection here; shear neglected), plus, on the DE bar,
      // the support's end skin under the largest moment F span: a root
      // rotation F span end_skin span / (E I), 3 end_skin of the tip's
      // F span^3 / (3 E I). At R = 2 cm: 10.9 % + 5.3 % = 16.2 %, measured
      // +16.9 % (at R = 1 cm: 6.2 % + 2.6 %, measured +6.9 %). The skin's
      // depth and softness are known to about half, so the DE bending error
      // must lie in [0.5, 1.5] x the estimate.
      const double a_eff = 1.0 - (1.0 - sk) * (1.0 - std::pow(1.0 - 2.0 * t, 2));
      const double i_eff = 1.0 - (1.0 - sk) * (1.0 - std::pow(1.0 - 2.0 * t, 4));
      const double lateral = a_eff / i_eff - 1.0;
      const double est_bending = lateral + (model == "de" ? 3.0 * end_skin : 0.0);
      INFO("skin estimates: tension " << est_tension << ", bending " << est_bending);
      if (model == "de" && load == "bending")
      {
        CHECK(err > 0.5 * est_bending);
        CHECK(err < 1.5 * est_bending);
        continue;
      }
      // the coupled bar's spheres start at the overlap: in bending their
      // lateral skins weigh by their share of the compliance, ~(1 - x / span)^3
      // from the overlap's middle (14 % here: 1.6 %; measured +0.6 %)
      const double x_mid = c.overlap_start + 0.5 * c.overlap_layers * c.fe_size;
      const double est = load == "tension" ? est_tension : std::pow(1.0 - x_mid / span, 3) * lateral;
      const double tol = model == "fe" ? 0.02 : 0.02 + est;
      CHECK(std::abs(err) < tol);
    }
    // the paper: the coupled model lies between the FE and DE ones (measured
    // tension -0.2 %, +0.7 %, +3.3 %; bending -0.6 %, +0.6 %, +16.9 %)
    INFO(load << ": static error FE " << errs[0] << ", coupled " << errs[1] << ", DE " << errs[2]);
    CHECK((errs[1] - errs[0]) * (errs[1] - errs[2]) <= 0.0);
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
