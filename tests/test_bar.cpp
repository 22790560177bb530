// The paper's validation bar, reduced: DE mean radius 1.4 cm (about 9 spheres
// across the 0.25 m section, 2,500 spheres in the all-DE bar) so all cases
// run in about 15 s. The full-size figures are in README (bar --compare).
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
  c.mean_radius = 0.014;
  c.material = DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json";
  c.quiet = true;
  return c;
}
} // namespace

// [long]: over 3 minutes under the sanitizers (scripts/sanitize.sh leaves it
// out; the code it runs is the bar demo's, which the other [bar] tests run too)
TEST_CASE("bar, reduced: static shapes against beam theory, dynamic frequencies agree", "[bar][long]")
{
  // the E the identified parameters give on this packing: DE static tension
  const double E = demo::bar_modulus(reduced("de", "tension", "static"));
  INFO("E measured on the DE bar " << E << " Pa");
  // The identification's 30 GPa is a section average of the calibration
  // cylinder (platen force over its area), skin included; this bar's skin is
  // compensated (dem/skin.h), so it shows nearer its bulk: 31.2 GPa in the
  // interior of the full-size bar without compensation, 32.0 GPa with it.
  // Within 10 %; measured 32.1 GPa (+7 %).
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
      // rigid plate (hinged at its centroid in bending). FE: the required 2 %
      // (measured -0.2 % tension, -0.6 % bending: the clamp holds the
      // Poisson contraction).
      // Spheres: the skins' links are stiffened to the bulk's links per
      // sphere. E is measured on the middle half, away from the end faces,
      // whose skins (one at the DE bar's support, one at each loaded end)
      // are compensated with factors over a crowd of edge and corner spheres
      // (up to 4x): their share of the span is known only to about their
      // uncompensated size, (12/7 - 1) R / span each (the layer at a face
      // lies flat on it with ~7 links per sphere against 12 in the bulk).
      // Hence 2 % plus that: 4.4 % (DE), 3.2 % (coupled). Measured tension
      // -0.2 %, -1.4 %, -2.1 %; bending -0.6 %, -0.7 %, -0.8 % (FE,
      // coupled, DE).
      const double end_skin = (12.0 / 7.0 - 1.0) * c.mean_radius / r.at("beam_span_m").get<double>();
      const double tol = model == "fe" ? 0.02 : 0.02 + (model == "de" ? 2.0 : 1.0) * end_skin;
      CHECK(std::abs(err) < tol);
    }
    // Not checked: that the coupled error lies between the FE and DE ones
    // (the paper's claim). Here it is decided by the packing, not by the
    // coupling: the DE bar's static error scatters between packings by more
    // than the three models differ (bending at this size: seed 1 FE -0.64 %,
    // coupled -0.70 %, DE -0.81 %, between; seed 2 -0.64 %, -1.09 %, -0.81 %,
    // not; full size over five seeds in README, `bar --compare --seeds`).
    INFO(load << ": static error FE " << errs[0] << ", coupled " << errs[1] << ", DE " << errs[2]);
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
    // the three discretisations of the same concrete: the required 2 %
    // (measured up to 1.3 %: tension FE 1078 Hz, coupled 1081, DE 1092;
    // bending 193.2, 194.0, 194.9)
    CHECK(std::abs(f[1] / f[2] - 1.0) < 0.02);
    CHECK(std::abs(f[1] / f[0] - 1.0) < 0.02);
  }
}

TEST_CASE("bar, reduced: without the skin compensation the DE bar is soft in bending", "[bar]")
{
  // The uncompensated DE bar against beam theory with the E it shows in
  // tension. Skin model: the layer at each face, one radius deep, lies flat
  // on it with ~7 links per sphere against 12 in the bulk (sk = 7/12 of the
  // bulk's stiffness). E (tension, middle half) holds the long faces' skins
  // as A_eff; bending weighs them as I_eff (z^2), plus the support's end
  // skin under the largest moment F span: a root rotation of 3 end_skin of
  // the tip's F span^3 / (3 E I). The skin's depth and softness are known to
  // about half: the error must lie in [0.5, 1.5] x the estimate. With the
  // compensation (test above) the same bar is within 2 %.
  auto c = reduced("de", "bending", "static");
  c.skin_compensation = false;
  c.fe_youngs_modulus = demo::bar_modulus(c);
  const auto r = demo::run_bar(c);
  const double err = r.at("static_relative_error").get<double>();
  const double sk = 7.0 / 12.0, s = c.mean_radius / c.width;
  const double a_eff = 1.0 - (1.0 - sk) * (1.0 - std::pow(1.0 - 2.0 * s, 2));
  const double i_eff = 1.0 - (1.0 - sk) * (1.0 - std::pow(1.0 - 2.0 * s, 4));
  const double end_skin = (1.0 / sk - 1.0) * c.mean_radius / r.at("beam_span_m").get<double>();
  const double est = a_eff / i_eff - 1.0 + 3.0 * end_skin;
  INFO("E " << c.fe_youngs_modulus << " Pa, bending error " << err << ", skin estimate " << est);
  CHECK(err > 0.5 * est);
  CHECK(err < 1.5 * est);
  CHECK(r.at("skin_compensation").at("on").get<bool>() == false);
}

TEST_CASE("bar --seeds: the scatter table from the per-seed tables", "[bar]")
{
  // three synthetic per-seed tables with known values: the means, sample
  // standard deviations and between counts are exact arithmetic
  auto table = [](double fe, double coupled, double de, double static_err)
  {
    nlohmann::json t;
    for (const std::string load : {"tension", "bending"})
    {
      for (const std::string probe : {"probe_0_75", "probe_0_4351"})
        for (const std::string q : {"first_frequency_hz", "amplitude_m"})
          t[load][probe][q] = {{"fe", fe}, {"coupled", coupled}, {"de", de},
                               {"coupled_vs_de", coupled / de - 1.0}, {"coupled_vs_fe", coupled / fe - 1.0},
                               {"between", (coupled - fe) * (coupled - de) <= 0.0}};
      for (const std::string model : {"fe", "coupled", "de"})
        t["static"][load][model] = {{"relative_error", static_err}};
    }
    return t;
  };
  // coupled between in the first two, above both in the third
  const std::vector<nlohmann::json> tables{table(100.0, 101.0, 102.0, -0.01), table(100.0, 101.0, 104.0, 0.0),
                                           table(100.0, 101.0, 100.0, 0.01)};
  std::string md;
  const auto s = demo::seeds_table({1, 2, 3}, tables, md);
  const auto& f = s.at("bending").at("probe_0_75").at("first_frequency_hz");
  CHECK(f.at("de").at("mean").get<double>() == Approx(102.0).epsilon(1e-14));
  CHECK(f.at("de").at("sd").get<double>() == Approx(2.0).epsilon(1e-14)); // sqrt((0 + 4 + 4) / 2)
  CHECK(f.at("coupled").at("sd").get<double>() == 0.0);
  CHECK(f.at("between").get<int>() == 2);
  CHECK(f.at("coupled_vs_de").size() == 3);
  CHECK(f.at("coupled_vs_de")[2].get<double>() == Approx(0.01).epsilon(1e-12));
  CHECK(s.at("static").at("tension").at("de").at("mean").get<double>() == Approx(0.0).margin(1e-15));
  CHECK(s.at("static").at("tension").at("de").at("sd").get<double>() == Approx(0.01).epsilon(1e-12));
  CHECK(md.find("| bending | first frequency | probe_0_75 |") != std::string::npos);
  CHECK(md.find("2 of 3") != std::string::npos);
  CHECK_THROWS_WITH(demo::seeds_table({1}, {tables[0]}, md), Catch::Contains("at least two seeds"));
  // many seeds: every per-seed value reaches the Markdown row
  std::vector<unsigned> many;
  std::vector<nlohmann::json> many_tables;
  for (unsigned k = 0; k < 30; ++k)
  {
    many.push_back(k + 1);
    many_tables.push_back(table(100.0, 101.0, k == 29 ? 100.5 : 102.0, 0.0)); // the last: coupled above both
  }
  demo::seeds_table(many, many_tables, md);
  CHECK(md.find("| tension | first frequency | probe_0_75 |") != std::string::npos);
  CHECK(md.find("+0.50 % | +1.00, ") != std::string::npos); // the 30th seed: 101 / 100.5 - 1, then vs FE
  CHECK(md.find("29 of 30 |") != std::string::npos);
}
