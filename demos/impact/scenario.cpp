#include "scenario.h"

#include "options.h"
#include "support.h"

#include "dembridge/dem/material_file.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <toml++/toml.h>

namespace dembridge::demo
{
namespace
{

/// "3.5", "7", "text": a TOML value as the user would write it.
std::string show(const toml::node& n)
{
  std::ostringstream s;
  if (auto str = n.as_string())
    s << '"' << str->get() << '"';
  else if (n.is_floating_point())
    s << std::setprecision(12) << n.value<double>().value();
  else if (auto arr = n.as_array())
    s << *arr;
  else if (n.is_table())
    s << "a table";
  else
    n.visit([&](const auto& v) { s << v; });
  return s.str();
}

std::string type_name(const toml::node& n)
{
  switch (n.type())
  {
  case toml::node_type::string: return "a string";
  case toml::node_type::integer: return "an integer";
  case toml::node_type::floating_point: return "a number";
  case toml::node_type::boolean: return "a boolean";
  case toml::node_type::array: return "an array";
  case toml::node_type::table: return "a table";
  default: return "a date or time";
  }
}


/// Reads the keys of one scenario, section by section, each with its
/// default, allowed values and meaning; records what was read (for the
/// unknown-key check) and the value used (Scenario::resolved).
class Reader
{
public:
  Reader(const toml::table& root, std::string file) : _root(root), _file(std::move(file)) {}

  void section(const std::string& name, const std::string& meaning)
  {
    _section = name;
    _known[name];
    _doc << "\n[" << name << "]  " << meaning << "\n";
    const toml::node* n = _root.get(name);
    if (n && !n->is_table())
      fail(name, "must be a table ([" + name + "]), not " + type_name(*n));
    _table = n ? n->as_table() : nullptr;
  }

  double number(const std::string& key, double def, const Allowed& allowed, const std::string& meaning)
  {
    const toml::node* n = get(key, meaning, number_text(def), allowed.text());
    double v = def;
    if (n)
    {
      if (!n->is_number())
        fail(key, "must be a number, not " + type_name(*n) + " (" + show(*n) + ")");
      v = n->value<double>().value();
      if (!std::isfinite(v) || !allowed.contains(v))
        fail(key, "= " + show(*n) + ": allowed " + allowed.text());
    }
    record(key, v);
    return v;
  }

  long integer(const std::string& key, long def, const Allowed& allowed, const std::string& meaning)
  {
    const toml::node* n = get(key, meaning, std::to_string(def), allowed.text());
    long v = def;
    if (n)
    {
      if (!n->is_integer())
        fail(key, "must be an integer, not " + type_name(*n) + " (" + show(*n) + ")");
      v = static_cast<long>(n->value<std::int64_t>().value());
      if (!allowed.contains(static_cast<double>(v)))
        fail(key, "= " + show(*n) + ": allowed " + allowed.text());
    }
    record(key, v);
    return v;
  }

  bool boolean(const std::string& key, bool def, const std::string& meaning)
  {
    const toml::node* n = get(key, meaning, def ? "true" : "false", "true | false");
    bool v = def;
    if (n)
    {
      if (!n->is_boolean())
        fail(key, "must be true or false, not " + type_name(*n) + " (" + show(*n) + ")");
      v = n->value<bool>().value();
    }
    record(key, v);
    return v;
  }

  std::string text(const std::string& key, const std::string& def, const std::string& choices,
                   const std::string& meaning)
  {
    const toml::node* n = get(key, meaning, def.empty() ? "\"\"" : "\"" + def + "\"", choices);
    std::string v = def;
    if (n)
    {
      if (!n->is_string())
        fail(key, "must be a string, not " + type_name(*n) + " (" + show(*n) + ")");
      v = n->value<std::string>().value();
      if (!choices.empty() && choices.find('|') != std::string::npos)
      {
        bool ok = false;
        std::istringstream in(choices);
        for (std::string c; in >> c;)
          ok = ok || (c != "|" && (c == v || (c == "\"\"" && v.empty())));
        if (!ok)
          fail(key, "= \"" + v + "\": allowed " + choices);
      }
    }
    record(key, v);
    return v;
  }

  template <std::size_t N>
  std::array<double, N> numbers(const std::string& key, const std::array<double, N>& def, const Allowed& allowed,
                                const std::string& meaning)
  {
    std::ostringstream d;
    d << "[";
    for (std::size_t k = 0; k < N; ++k)
      d << (k ? ", " : "") << number_text(def[k]);
    d << "]";
    const toml::node* n = get(key, meaning, d.str(), std::to_string(N) + " numbers, each " + allowed.text());
    std::array<double, N> v = def;
    if (n)
    {
      const toml::array* a = n->as_array();
      if (!a || a->size() != N)
        fail(key, "must be an array of " + std::to_string(N) + " numbers, not " + show(*n));
      for (std::size_t k = 0; k < N; ++k)
      {
        const toml::node& e = *a->get(k);
        if (!e.is_number())
          fail(key, "must be an array of " + std::to_string(N) + " numbers, not " + show(*n));
        v[k] = e.value<double>().value();
        if (!std::isfinite(v[k]) || !allowed.contains(v[k]))
          fail(key, "= " + show(*n) + ": each allowed " + allowed.text());
      }
    }
    record(key, nlohmann::json(v));
    return v;
  }

  /// An array of polylines, each an array of points [x, y, z].
  std::vector<std::vector<std::array<double, 3>>> polylines(const std::string& key, const std::string& meaning)
  {
    const toml::node* n = get(key, meaning, "[]", "an array of polylines, each an array of >= 2 points [x, y, z]");
    std::vector<std::vector<std::array<double, 3>>> lines;
    nlohmann::json rec = nlohmann::json::array();
    if (n)
    {
      const std::string expect = "must be an array of polylines, each an array of >= 2 points [x, y, z] in m, not ";
      const toml::array* a = n->as_array();
      if (!a)
        fail(key, expect + show(*n));
      for (const toml::node& ln : *a)
      {
        const toml::array* pts = ln.as_array();
        if (!pts || pts->size() < 2)
          fail(key, expect + show(ln));
        std::vector<std::array<double, 3>> line;
        for (const toml::node& pt : *pts)
          line.push_back(point<3>(key, pt, expect));
        lines.push_back(line);
        rec.push_back(line);
      }
    }
    record(key, rec);
    return lines;
  }

  /// An array of points [x, y] [m] (empty by default).
  std::vector<std::array<double, 2>> points(const std::string& key, const std::string& meaning)
  {
    const toml::node* n = get(key, meaning, "[]", "an array of points [x, y]");
    std::vector<std::array<double, 2>> pts;
    if (n)
    {
      const std::string expect = "must be an array of points [x, y] in m, not ";
      const toml::array* a = n->as_array();
      if (!a)
        fail(key, expect + show(*n));
      for (const toml::node& pt : *a)
        pts.push_back(point<2>(key, pt, expect));
    }
    record(key, pts);
    return pts;
  }

  /// One point [x, y(, z)] of finite numbers, or an error saying `expect`.
  template <std::size_t N>
  std::array<double, N> point(const std::string& key, const toml::node& pt, const std::string& expect) const
  {
    const toml::array* c = pt.as_array();
    if (!c || c->size() != N)
      fail(key, expect + show(pt));
    std::array<double, N> x{};
    for (std::size_t k = 0; k < N; ++k)
    {
      if (!c->get(k)->is_number())
        fail(key, expect + show(pt));
      x[k] = c->get(k)->value<double>().value();
      if (!std::isfinite(x[k]))
        fail(key, expect + show(pt));
    }
    return x;
  }

  /// @throws std::runtime_error naming the file and the section's key.
  [[noreturn]] void fail(const std::string& key, const std::string& what) const
  {
    throw std::runtime_error("scenario " + _file + ": " + (key == _section ? key : _section + "." + key) + " " + what);
  }

  /// Every key of the file must have been read.
  void check_unknown() const
  {
    for (const auto& [name, node] : _root)
    {
      const std::string s(name.str());
      const auto known = _known.find(s);
      if (known == _known.end())
      {
        std::string list;
        for (const auto& [k, keys] : _known)
          list += (list.empty() ? "" : ", ") + k;
        throw std::runtime_error("scenario " + _file + ": unknown section or key '" + s + "' (sections: " + list + ")");
      }
      if (!node.is_table())
        continue;
      for (const auto& [key, value] : *node.as_table())
      {
        const std::string k(key.str());
        if (!known->second.count(k))
        {
          std::string list;
          for (const auto& q : known->second)
            list += (list.empty() ? "" : ", ") + q;
          throw std::runtime_error("scenario " + _file + ": unknown key '" + s + "." + k + "' ([" + s
                                   + "] takes: " + list + ")");
        }
      }
    }
  }

  const nlohmann::json& resolved() const { return _resolved; }
  std::string doc() const { return _doc.str(); }
  bool given(const std::string& key) const { return _table && _table->get(key); }

private:
  const toml::node* get(const std::string& key, const std::string& meaning, const std::string& def,
                        const std::string& allowed)
  {
    _known[_section].insert(key);
    _doc << "  " << key << " = " << def << "\n      " << meaning << (allowed.empty() ? "" : "; allowed: " + allowed)
         << "\n";
    return _table ? _table->get(key) : nullptr;
  }
  void record(const std::string& key, const nlohmann::json& v) { _resolved[_section + "." + key] = v; }

  const toml::table& _root;
  std::string _file;
  std::string _section;
  const toml::table* _table = nullptr;
  std::map<std::string, std::set<std::string>> _known;
  nlohmann::json _resolved = nlohmann::json::object();
  std::ostringstream _doc;
};

/// Applies one --set key=value to the parsed file.
void apply_set(toml::table& root, const std::string& set)
{
  const auto eq = set.find('=');
  const std::string key = set.substr(0, eq);
  const auto dot = key.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot == 0 || dot + 1 == key.size())
    throw std::runtime_error("--set '" + set + "': expected section.key=value (e.g. projectile.velocity_m_s=600)");
  const std::string section = key.substr(0, dot), name = key.substr(dot + 1), text = set.substr(eq + 1);
  toml::table value;
  try
  {
    value = toml::parse("v = " + text);
  }
  catch (const toml::parse_error&)
  {
    value.insert_or_assign("v", text); // a bare word: a string
  }
  toml::node* s = root.get(section);
  if (!s)
  {
    root.insert_or_assign(section, toml::table{});
    s = root.get(section);
  }
  if (!s->is_table())
    throw std::runtime_error("--set '" + set + "': " + section + " is not a section");
  s->as_table()->insert_or_assign(name, *value.get("v"));
}

std::filesystem::path beside(const std::filesystem::path& scenario, const std::string& name)
{
  const std::filesystem::path p(name);
  return p.is_relative() && scenario.has_parent_path() ? scenario.parent_path() / p : p;
}

std::string default_material()
{
  return shipped_file("materials/default.json", DEMBRIDGE_SOURCE_DIR "/demos/calibrate/materials/default.json");
}

/// The [material] section: the file, then its values overridden.
MaterialSpec read_material_section(Reader& r, const std::filesystem::path& scenario)
{
  r.section("material", "the concrete: a material file of calibrate, any of its values overridden");
  MaterialSpec m;
  const std::string file = r.text("file", "", "",
                                  "DE parameter file (JSON, from calibrate), relative to the scenario's folder; "
                                  "\"\" = the shipped default concrete");
  m.file = file.empty() ? default_material() : beside(scenario, file).string();
  dem::MaterialFile f;
  try
  {
    f = dem::read_material(m.file);
  }
  catch (const std::exception& e)
  {
    r.fail("file", "= \"" + file + "\": " + e.what());
  }
  dem::Material& c = f.material;
  const Allowed angle{0.0, 90.0, false, true, {}, {}};
  c.youngs_modulus = r.number("youngs_modulus_pa", c.youngs_modulus, Allowed::positive(1e13), "E of equation [1] [Pa] (default: the file's)");
  c.poisson_ratio = r.number("poisson_ratio", c.poisson_ratio, Allowed::open(-1.0, 0.5), "nu of equation [1] [-]");
  c.density = r.number("density_kg_m3", c.density, Allowed::positive(1e5), "bulk density [kg/m^3]");
  c.micro.alpha = r.number("alpha", c.micro.alpha, Allowed::closed(-1e3, 1e3), "alpha of equation [1] [-]");
  c.micro.beta = r.number("beta", c.micro.beta, Allowed::closed(-1e3, 1e3), "beta of equation [1] [-]");
  c.micro.gamma = r.number("gamma", c.micro.gamma, Allowed::closed(-1e3, 1e3), "gamma of equation [1] [-]");
  c.tensile = r.number("tensile_strength_pa", c.tensile, Allowed::non_negative(1e12), "local tensile strength T [Pa]");
  c.cohesion = r.number("cohesion_pa", c.cohesion, Allowed::non_negative(1e12), "cohesion C0 [Pa]");
  c.zeta = r.number("softening", c.zeta, Allowed::non_negative(1e6), "softening factor zeta [-]");
  c.phi_i_deg = r.number("phi_i_deg", c.phi_i_deg, angle, "internal friction angle [degree]");
  c.phi_c_deg = r.number("phi_c_deg", c.phi_c_deg, angle, "contact friction angle [degree]");
  c.contact_shear_limit = r.number("contact_shear_limit_pa", c.contact_shear_limit,
                                   Allowed::positive(1e12).or_value(0.0, "no limit"),
                                   "Tresca limit of the contacts' friction: their largest shear stress [Pa]");
  c.crack_closure = r.number("crack_closure", c.crack_closure, Allowed::above(0.0, 1.0).or_value(0.0, "off"),
                             "crack closure: the share of a broken link's gap at rest, D_init - (R_a + R_b), at "
                             "which its spheres meet again, with the link's stiffnesses [-]; 1 = at D_init");
  c.rolling_friction = r.number("rolling_friction", c.rolling_friction, Allowed::positive(10.0).or_value(0.0, "none"),
                                "rolling resistance of the contacts: mu_r of the cap |M| <= mu_r R* F_c [-]");
  c.rate_fc = r.number("rate_fc_pa", c.rate_fc, Allowed::positive(1e10).or_value(0.0, "no rate effect"),
                       "strain-rate effect: the Malvar-Ross law's compressive strength f_c [Pa]");
  c.rate_cohesion = r.boolean("rate_cohesion", c.rate_cohesion,
                              "strain-rate effect: the factor multiplies C0 as well as T (false: T alone)");
  c.rate_mean_tension = r.boolean("rate_mean_tension", c.rate_mean_tension,
                                  "strain-rate effect: a link's factor grows only while its spheres' links are, "
                                  "on the whole, stretched");
  c.rate_current = r.boolean("rate_current", c.rate_current,
                             "strain-rate effect: a link's factor follows its current rate, not the largest so far "
                             "(never below what the link holds)");
  c.rate_filter = r.number("rate_filter_s", c.rate_filter, Allowed::positive(1.0).or_value(0.0, "no filter"),
                           "strain-rate effect: time constant of the low-pass filter on each link's rate [s]");
  c.rate_max = r.number("rate_max_1_s", c.rate_max, Allowed::positive(1e9).or_value(0.0, "no cap"),
                        "strain-rate effect: the rate above which the factor stops growing [1/s]");
  c.compaction.onset = r.number("compaction_onset", c.compaction.onset, Allowed::open(0.0, 1.0).or_value(0.0, "no compaction"),
                                "compaction: the links' compressive strain where pores start to collapse [-]");
  c.compaction.stiffness = r.number("compaction_stiffness", c.compaction.stiffness, Allowed::above(0.0, 1.0),
                                    "compaction: the links' tangent stiffness while pores collapse, over K_n [-]");
  c.compaction.lock = r.number("compaction_lock", c.compaction.lock > 0.0 ? c.compaction.lock : 0.05,
                               Allowed::open(0.0, 1.0),
                               "compaction: the compressive strain where the pores are closed (K_n again), above "
                               "the onset [-]");
  c.compaction.pressure = r.number("compaction_pressure_pa", c.compaction.pressure,
                                   Allowed::positive(1e12).or_value(0.0, "no gate"),
                                   "compaction: a link starts compacting only while its spheres' mean pressure is at "
                                   "least this [Pa]");
  m.links_per_sphere = r.number("links_per_sphere", f.links_per_sphere, Allowed::positive(100.0),
                                "mean links per sphere in the bulk (sets lambda) [-]");
  m.material = c; // validated once every key is known (read_scenario)
  m.steel = f.steel;
  m.bond = f.bond;
  return m;
}

TargetSpec read_target(Reader& r)
{
  r.section("target", "the slab: x, y in [-size/2, size/2], z in [-thickness, 0], struck at z = 0");
  TargetSpec t;
  t.size = r.numbers<2>("size_m", t.size, Allowed::positive(100.0), "lateral sizes along x and y [m]");
  t.thickness = r.number("thickness_m", t.thickness, Allowed::positive(100.0), "thickness along z [m]");
  t.mean_radius = r.number("mean_radius_m", t.mean_radius, Allowed::positive(1.0), "mean sphere radius [m]");
  t.radius_ratio = r.number("radius_ratio", t.radius_ratio, Allowed::closed(1.0, 3.0), "Rmax / Rmin [-]");
  t.seed = static_cast<unsigned>(r.integer("seed", t.seed, Allowed::closed(0, 4294967295.0), "packing random seed"));
  t.packing_file = r.text("packing_file", "", "",
                          "read the packing ('x y z r' [m], e.g. a run's packing.txt) instead of generating it, "
                          "relative to the scenario's folder; \"\" = generate");
  t.supports = r.text("supports", t.supports, "sides | rear-edges | frame | none",
                      "sides: the spheres of the four lateral faces held; rear-edges: those of the rear face "
                      "within support_width_m of its edges; frame: the slab rests on a rigid frame under that "
                      "strip, free to lift off (docs/impact.md); none: free");
  t.support_width = r.number("support_width_m", t.support_width, Allowed::positive(10.0).or_value(0.0, "2 Rmax"),
                             "width of the band held, or of the frame (needed with frame) [m]");
  t.fine_radius = r.number("fine_radius_m", t.fine_radius, Allowed::positive(100.0).or_value(0.0, "none"),
                           "finer spheres within this distance of the projectile's path, through the whole "
                           "thickness (docs/impact.md) [m]");
  t.fine_mean_radius = r.number("fine_mean_radius_m", t.fine_mean_radius,
                                Allowed::positive(1.0).or_value(0.0, "mean_radius_m / 2"),
                                "mean radius of the finer spheres (below mean_radius_m) [m]");
  t.fine_transition = r.number("fine_transition_m", t.fine_transition,
                               Allowed::positive(100.0).or_value(0.0, "4 mean_radius_m"),
                               "beyond fine_radius_m, the width over which the radii grow to mean_radius_m [m]");
  t.skin_compensation = r.boolean("skin_compensation", t.skin_compensation,
                                  "stiffen the links of the spheres within 2 Rmax of the slab's faces by the links "
                                  "they miss (docs/impact.md, \"Elastic checks\"): a slab a few spheres thick is "
                                  "soft in bending without it; strengths unchanged");
  return t;
}

ReinforcementSpec read_reinforcement(Reader& r, const MaterialSpec& m)
{
  r.section("reinforcement", "steel bars in the slab, bonded to the concrete (docs/method.md 1.15); the steel and "
                             "bond default to the material file's, if it has them");
  ReinforcementSpec b;
  if (m.steel)
    b.steel = *m.steel;
  if (m.bond)
    b.bond = *m.bond;
  b.layers = static_cast<int>(r.integer("layers", b.layers, Allowed::closed(0, 100),
                                        "mats of bars along x and y, spread through the thickness (one: at the "
                                        "rear face); 0 = none"));
  b.bar_diameter = r.number("bar_diameter_m", b.bar_diameter, Allowed::positive(1.0).or_value(0.0, "no bars"),
                            "bar diameter, of the mats and the polylines [m]");
  b.spacing = r.numbers<2>("spacing_m", b.spacing, Allowed::positive(100.0),
                           "distance between neighbouring bars along x, and between those along y [m]");
  b.cover = r.number("cover_m", b.cover, Allowed::positive(10.0).or_value(0.0, "2 bar diameters"),
                     "from each face to the axis of the bars nearest to it (>= the bar radius) [m]");
  b.polylines = r.polylines("bars_m", "bars given as polylines, e.g. [[[x0, y0, z0], [x1, y1, z1]]] [m]");
  dem::Steel& st = b.steel;
  st.youngs_modulus = r.number("steel_youngs_modulus_pa", st.youngs_modulus, Allowed::positive(1e13), "E_s [Pa]");
  st.density = r.number("steel_density_kg_m3", st.density, Allowed::positive(1e5), "[kg/m^3]");
  st.yield = r.number("steel_yield_pa", st.yield, Allowed::positive(1e11), "yield strength f_y [Pa]");
  st.hardening = r.number("steel_hardening_pa", st.hardening, Allowed::non_negative(1e13),
                          "hardening modulus H = d sigma / d plastic strain [Pa]");
  st.rupture_strain = r.number("steel_rupture_strain", st.rupture_strain, Allowed::positive(10.0),
                               "strain at which a bar breaks (above f_y / E_s) [-]");
  dem::BondLaw& bl = b.bond;
  bl.tau_max = r.number("bond_tau_max_pa", bl.tau_max, Allowed::positive(1e10),
                        "peak bond stress (fib MC2010, good bond: 2.5 sqrt(f_cm[MPa]) MPa) [Pa]");
  bl.s0 = r.number("bond_s0_m", bl.s0, Allowed::positive(1.0), "end of the bond law's linear start (< s1) [m]");
  bl.s1 = r.number("bond_s1_m", bl.s1, Allowed::positive(1.0), "slip at the peak [m]");
  bl.s2 = r.number("bond_s2_m", bl.s2, Allowed::positive(1.0), "end of the plateau (>= s1) [m]");
  bl.s3 = r.number("bond_s3_m", bl.s3, Allowed::positive(1.0), "end of the descent (> s2; fib: the clear rib spacing) [m]");
  bl.alpha = r.number("bond_alpha", bl.alpha, Allowed::above(0.0, 1.0), "exponent of the rising branch [-]");
  bl.tau_f_ratio = r.number("bond_tau_f_ratio", bl.tau_f_ratio, Allowed::closed(0.0, 1.0),
                            "residual bond stress over the peak [-]");
  bl.radial_stiffness = r.number("bond_radial_stiffness_pa_m", bl.radial_stiffness, Allowed::positive(1e20),
                                 "radial stiffness per unit bar surface [Pa/m]");
  bl.opening = r.number("bond_opening_pa", bl.opening, Allowed::positive(1e10),
                        "radial tensile strength of the bar-concrete interface [Pa]");
  bl.opening_gap = r.number("bond_opening_gap_m", bl.opening_gap, Allowed::positive(1.0),
                            "radial gap at which the bond opens (> opening / radial stiffness) [m]");
  b.element_length = r.number("element_length_m", b.element_length,
                              Allowed::positive(10.0).or_value(0.0, "the mean sphere diameter"),
                              "length of the bars' elements, at most [m]");
  b.bond_reach = r.number("bond_reach_m", b.bond_reach, Allowed::non_negative(1.0).or_value(0.0, "half the mean radius"),
                          "a sphere is bonded when its surface lies within this of a bar's [m]");
  b.embedded = r.boolean("embedded", b.embedded,
                         "true (the default): the slab is packed as without bars, the bars lie inside it, bonded to "
                         "the spheres they cross and meeting the spheres only through bonds; false: the packing leaves "
                         "the bars room and spheres beyond their bonds are pushed off the bars, which weakens the slab "
                         "in the mats' planes (docs/impact.md)");
  return b;
}

ProjectileSpec read_projectile(Reader& r)
{
  r.section("projectile", "the rigid projectile: a cylinder shank and its nose, axis along its path");
  ProjectileSpec p;
  p.mass = r.number("mass_kg", p.mass, Allowed::positive(1e6).or_value(0.0, "from density_kg_m3 and the shape"),
                    "mass [kg]");
  p.density = r.number("density_kg_m3", p.density, Allowed::positive(1e5), "solid density, when mass_kg = 0 [kg/m^3]");
  p.diameter = r.number("diameter_m", p.diameter, Allowed::positive(10.0), "shank diameter [m]");
  p.length = r.number("length_m", p.length, Allowed::positive(100.0), "overall length, tip to tail [m]");
  p.nose = r.text("nose", p.nose, "flat | hemispherical | conical | ogive", "nose shape");
  p.crh = r.number("crh", p.crh, Allowed{0.5, 1e3, false, true, {}, {}},
                   "ogive: caliber-radius-head psi (arc radius psi x diameter) [-]");
  p.cone_angle_deg = r.number("cone_angle_deg", p.cone_angle_deg, Allowed::open(0.0, 90.0), "conical: tip half-angle [degree]");
  p.velocity = r.number("velocity_m_s", p.velocity, Allowed::positive(1e4), "striking speed [m/s]");
  p.obliquity_deg = r.number("obliquity_deg", p.obliquity_deg, Allowed{0.0, 90.0, false, true, {}, {}},
                             "angle of the path to the face's normal, tilted towards +x [degree]");
  p.aim = r.numbers<2>("aim_m", p.aim, Allowed::closed(-100.0, 100.0), "where the path meets the struck face (x, y) [m]");
  p.standoff = r.number("standoff_m", p.standoff, Allowed::positive(10.0), "tip to the face at the start, along the path [m]");
  p.friction = r.number("friction", p.friction, Allowed::closed(0.0, 10.0), "Coulomb coefficient with the concrete [-]");
  return p;
}

RunSpec read_run(Reader& r)
{
  r.section("run", "the time loop and the outputs");
  RunSpec s;
  s.duration = r.number("duration_s", s.duration, Allowed::positive(10.0).or_value(0.0, "automatic"),
                        "physical time simulated at most: the run ends when the projectile stops or has cleared "
                        "the slab; automatic: 4 x the crossing time (standoff + thickness + length) / velocity [s]");
  s.dt = r.number("dt_s", s.dt, Allowed::positive(1.0).or_value(0.0, "safety_factor x critical"), "time step [s]");
  s.safety = r.number("safety_factor", s.safety, Allowed::above(0.0, 1.0),
                      "fraction of the critical time step (links and projectile contact) [-]");
  s.damping = r.number("damping_1_s", s.damping, Allowed::non_negative(1e9), "velocity-proportional damping [1/s]");
  s.frames = static_cast<int>(r.integer("frames", s.frames, Allowed::closed(1, 100000), "XDMF frames over the crossing time (the same pace after it)"));
  s.history_every = static_cast<int>(r.integer("history_every", s.history_every,
                                               Allowed::closed(1, 1e9).or_value(0, "250 rows over the crossing time"),
                                               "steps between rows of history.csv"));
  s.domain_margin = r.number("domain_margin_m", s.domain_margin, Allowed::positive(100.0).or_value(0.0, "the thickness"),
                             "spheres farther than this from the slab are removed (fragments) [m]");
  s.skin = r.number("neighbour_skin_m", s.skin, Allowed::positive(1.0).or_value(0.0, "half the smallest radius"),
                    "neighbour-list skin: pairs closer than contact + skin are listed, a sphere searched again "
                    "once it has moved 0.3 skin [m]");
  return s;
}

ShellSpec read_shells(Reader& r)
{
  r.section("shells", "the slab's model: all DE, or a DE core round the impact coupled to reinforced-concrete "
                      "shells over the rest (docs/impact.md, \"Coupled slabs\")");
  ShellSpec s;
  s.model = r.text("model", s.model, "de | coupled | fe",
                   "de: the whole slab of spheres; coupled: spheres in the core and its band only, shells of the "
                   "concrete's E and nu with the mats' steel as layers elsewhere; fe: the whole slab of those "
                   "shells, loaded by the [pulse] (elastic checks) (impact --model sets it)");
  s.core = r.text("core", s.core, "cylinder | box", "the DE core's shape, through the thickness, centred on "
                                                     "projectile.aim_m");
  s.core_radius = r.number("core_radius_m", s.core_radius, Allowed::positive(100.0).or_value(0.0, "none"),
                           "cylinder core's radius (needed with model coupled and core cylinder) [m]");
  s.core_size = r.numbers<2>("core_size_m", s.core_size, Allowed::non_negative(100.0),
                             "box core's sizes along x and y (needed with model coupled and core box) [m]");
  s.band = r.number("band_m", s.band, Allowed::positive(100.0).or_value(0.0, "8 target.mean_radius_m"),
                    "width of the overlap round the core, where spheres and shells share the slab [m]");
  s.element_size = r.number("element_size_m", s.element_size, Allowed::positive(100.0).or_value(0.0, "band_m / 2"),
                            "the shells' element size (Gmsh; at most band_m) [m]");
  s.outer_element_size = r.number("outer_element_size_m", s.outer_element_size,
                                  Allowed::positive(100.0).or_value(0.0, "element_size_m"),
                                  "the shells' element size at the slab's corners, graded from element_size_m at the "
                                  "core [m]");
  s.cell = r.text("cell", s.cell, "quadrilateral | triangle", "the shells' elements");
  s.edges = r.text("edges", s.edges, "\"\" | free | simply-supported | clamped | frame",
                   "the shells' outer edges (frame: resting on target.supports' frame, free to lift off); \"\" = "
                   "as target.supports (sides: clamped, rear-edges: simply supported, frame: frame, none: free)");
  s.weight_floor = r.number("weight_floor", s.weight_floor, Allowed::open(0.0, 1.0),
                            "floor of the weighted masses in the overlap [-]");
  s.deflection_points = r.points("deflection_points_m", "points (x, y) whose deflection (u_z; u_x under an "
                                                         "in-plane pulse) history.csv and the summary follow: on "
                                                         "shells interpolated in the element at the mid-surface, "
                                                         "with spheres there the mean of those within 2 mean "
                                                         "radii in plan [m]");
  return s;
}

PulseSpec read_pulse(Reader& r)
{
  r.section("pulse", "a prescribed load in place of the projectile, for elastic checks of the three models: a "
                     "half-sine force spread over a disc centred on projectile.aim_m "
                     "(docs/impact.md, \"Elastic checks\")");
  PulseSpec p;
  p.peak_force = r.number("peak_force_n", p.peak_force, Allowed::positive(1e12).or_value(0.0, "none: the projectile"),
                          "the pulse's peak force [N]");
  p.duration = r.number("duration_s", p.duration, Allowed::positive(10.0).or_value(0.0, "none"),
                        "the half sine's duration (needed with peak_force_n) [s]");
  p.radius = r.number("radius_m", p.radius, Allowed::positive(100.0).or_value(0.0, "projectile.diameter_m / 2"),
                      "the loaded disc's radius [m]");
  p.direction = r.text("direction", p.direction, "-z | x",
                       "-z: on the struck face, normal to it (bending); x: in the slab's plane, over the disc "
                       "through the whole thickness (membrane)");
  return p;
}

/// A frame needs its width, and leaves the slab's face room inside it.
void check_frame(const Scenario& s)
{
  const TargetSpec& t = s.target;
  const bool shells_frame = s.shells.edges == "frame" && s.shells.model != "de";
  if (t.supports != "frame" && !shells_frame)
    return;
  const std::string at = "scenario " + s.file.string() + ": ";
  const std::string who = t.supports == "frame" ? "target.supports = \"frame\"" : "shells.edges = \"frame\"";
  if (!(t.support_width > 0.0))
    throw std::runtime_error(at + who + " needs target.support_width_m > 0: the frame's width under the rear "
                             "face's edges");
  if (!(2.0 * t.support_width < std::min(t.size[0], t.size[1])))
    throw std::runtime_error(at + "target.support_width_m = " + number_text(t.support_width) + " m: the frame "
                             "must leave the slab's plan (target.size_m = [" + number_text(t.size[0]) + ", "
                             + number_text(t.size[1]) + "] m) open inside it: below half the smaller size");
}

/// The pulse's own checks and what it asks of the run (a duration).
void check_pulse(const Scenario& s)
{
  const PulseSpec& p = s.pulse;
  const std::string at = "scenario " + s.file.string() + ": ";
  if (s.shells.shells_only() && !p.any())
    throw std::runtime_error(at + "shells.model = \"fe\" needs a pulse (pulse.peak_force_n > 0): the shells "
                             "neither fracture nor meet a projectile");
  if (!p.any())
    return;
  if (!(p.duration > 0.0))
    throw std::runtime_error(at + "pulse.duration_s = 0: give the pulse's duration (> 0 s) with pulse.peak_force_n");
  if (!(s.run.duration > 0.0))
    throw std::runtime_error(at + "run.duration_s = 0 with a pulse: give the time to simulate (> 0 s; the "
                             "automatic one follows a projectile)");
  const double r = p.radius > 0.0 ? p.radius : 0.5 * s.projectile.diameter;
  const auto& a = s.projectile.aim;
  if (std::abs(a[0]) + r >= 0.5 * s.target.size[0] || std::abs(a[1]) + r >= 0.5 * s.target.size[1])
    throw std::runtime_error(at + pulse_radius_text(s) + " about projectile.aim_m = ["
                             + number_text(a[0]) + ", " + number_text(a[1]) + "]: the loaded disc must lie inside "
                             "the slab's face (target.size_m = [" + number_text(s.target.size[0]) + ", "
                             + number_text(s.target.size[1]) + "] m)");
}

Scenario read_sections(Reader& r, const std::filesystem::path& file)
{
  Scenario s;
  s.file = file;
  r.section("scenario", "what the case is");
  s.name = r.text("name", "impact", "", "the case's name (in the summary and plots)");
  s.material = read_material_section(r, file);
  s.target = read_target(r);
  s.reinforcement = read_reinforcement(r, s.material);
  s.projectile = read_projectile(r);
  s.run = read_run(r);
  s.shells = read_shells(r);
  s.pulse = read_pulse(r);
  s.resolved = r.resolved();
  s.resolved["material.file"] = s.material.file;
  if (!s.target.packing_file.empty())
  {
    // relative to the scenario's folder, as material.file
    s.target.packing_file = beside(file, s.target.packing_file).string();
    s.resolved["target.packing_file"] = s.target.packing_file;
  }
  return s;
}

/// The projectile must strike the slab's face whole: its footprint on the
/// struck face (its cross-section cut by the face: the radius r across the
/// plane of obliquity, r / cos(obliquity) along x) lies at least that far
/// from each edge of the face around projectile.aim_m. A path beside the
/// slab, or one grazing its edge, would give no impact, or one on an edge
/// that the slab's supports and size do not model. (Where an oblique path
/// would leave a thick slab is not checked: a block may stop it first.)
void check_path(const Scenario& s)
{
  const TargetSpec& t = s.target;
  const ProjectileSpec& q = s.projectile;
  const std::string at = "scenario " + s.file.string() + ": ";
  const double r = 0.5 * q.diameter, rx = r / std::cos(q.obliquity_deg * std::numbers::pi / 180.0);
  const double ax = 0.5 * t.size[0] - rx, ay = 0.5 * t.size[1] - r;
  if (ax <= 0.0 || ay <= 0.0)
    throw std::runtime_error(at + "projectile.diameter_m = " + number_text(q.diameter) + ": the projectile (its "
                             "footprint on the face " + number_text(2.0 * rx) + " x " + number_text(q.diameter)
                             + " m at obliquity_deg " + number_text(q.obliquity_deg) + ") is not narrower than the "
                             "slab (target.size_m = [" + number_text(t.size[0]) + ", " + number_text(t.size[1])
                             + "] m): give a wider slab or a narrower projectile");
  if (std::abs(q.aim[0]) > ax || std::abs(q.aim[1]) > ay)
    throw std::runtime_error(at + "projectile.aim_m = [" + number_text(q.aim[0]) + ", " + number_text(q.aim[1])
                             + "]: the projectile (diameter " + number_text(q.diameter) + " m) would miss the slab "
                             "or graze its edge: allowed |x| <= " + number_text(ax) + " m and |y| <= "
                             + number_text(ay) + " m (the slab's half sizes, target.size_m / 2, less the "
                             "projectile's footprint: its radius, over cos(obliquity_deg) along x)");
}

} // namespace

std::string pulse_radius_text(const Scenario& s)
{
  const PulseSpec& p = s.pulse;
  return p.radius > 0.0 ? "pulse.radius_m = " + number_text(p.radius) + " m"
                        : "pulse.radius_m = 0 (projectile.diameter_m / 2 = " + number_text(0.5 * s.projectile.diameter)
                              + " m)";
}

double PulseSpec::force(double t) const
{
  return t >= 0.0 && t <= duration ? peak_force * std::sin(std::numbers::pi * t / duration) : 0.0;
}

std::string number_text(double v)
{
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

Scenario read_scenario(const std::filesystem::path& file, const std::vector<std::string>& sets)
{
  toml::table root;
  if (!std::filesystem::is_regular_file(file))
    throw std::runtime_error("scenario " + file.string() + ": no such file (give a scenario file, or the name of "
                             "a shipped one: small, small-rc, small-slab, elastic-slab, hanchak-48, semi-infinite)");
  try
  {
    root = toml::parse_file(file.string());
  }
  catch (const toml::parse_error& e)
  {
    std::ostringstream s;
    s << "scenario " << file.string() << ": line " << e.source().begin.line << ", column " << e.source().begin.column
      << ": " << e.description();
    throw std::runtime_error(s.str());
  }
  for (const auto& set : sets)
    apply_set(root, set);
  Reader r(root, file.string());
  Scenario s = read_sections(r, file);
  r.check_unknown(); // a misspelt key first, then the values' consistency
  try
  {
    s.material.material.validate();
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("scenario " + file.string() + ": [material]: " + e.what());
  }
  const ReinforcementSpec& b = s.reinforcement;
  try
  {
    b.steel.validate();
    b.bond.validate();
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("scenario " + file.string() + ": [reinforcement]: " + e.what());
  }
  if (b.any() && !(b.bar_diameter > 0.0))
    throw std::runtime_error("scenario " + file.string() + ": reinforcement.bar_diameter_m = 0: give the bars' "
                             "diameter (> 0 m) with layers or bars_m");
  bar_lines(s); // the layout's own checks
  check_pulse(s);
  check_frame(s);
  const auto& pts = s.shells.deflection_points;
  for (std::size_t q = 0; q < pts.size(); ++q)
    if (std::abs(pts[q][0]) > 0.5 * s.target.size[0] || std::abs(pts[q][1]) > 0.5 * s.target.size[1])
      throw std::runtime_error("scenario " + file.string() + ": shells.deflection_points_m: point " + std::to_string(q)
                               + " (" + number_text(pts[q][0]) + ", " + number_text(pts[q][1]) + ") m lies outside "
                               "the slab's plan (target.size_m = [" + number_text(s.target.size[0]) + ", "
                               + number_text(s.target.size[1]) + "] m)");
  if (!s.pulse.any()) // a pulse loads the slab in the projectile's place: only its aim is used
  {
    check_path(s);
    try
    {
      projectile_shape(s.projectile);
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error("scenario " + file.string() + ": " + e.what());
    }
  }
  const TargetSpec& t = s.target;
  if (!t.packing_file.empty() && !std::filesystem::is_regular_file(t.packing_file))
    throw std::runtime_error("scenario " + file.string() + ": target.packing_file = \"" + t.packing_file
                             + "\": no such file (a relative name is taken from the scenario's folder)");
  if (t.fine())
  {
    const std::string at = "scenario " + file.string() + ": target.";
    if (!(t.fine_mean() < t.mean_radius))
      throw std::runtime_error(at + "fine_mean_radius_m = " + number_text(t.fine_mean()) + ": allowed below "
                               "target.mean_radius_m (" + number_text(t.mean_radius) + " m)");
    if (!t.packing_file.empty())
      throw std::runtime_error(at + "fine_radius_m = " + number_text(t.fine_radius) + " with a packing_file: "
                               "the file's spheres are used as they are; give one or the other");
  }
  return s;
}

std::string scenario_keys()
{
  const toml::table empty;
  Reader r(empty, "");
  read_sections(r, ""); // an empty file: every key at its default
  return r.doc();
}

} // namespace dembridge::demo
