// The bar's comparison (bar.h): the twelve runs of --compare, the paper's
// table from them, and the table over several packings (--seeds).
#include "bar.h"
#include "support.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

namespace dembridge::demo
{

nlohmann::json compare_table(const nlohmann::json& runs, std::string& md)
{
  nlohmann::json table;
  std::ostringstream m;
  auto rel = [](double a, double b) { return a / b - 1.0; };
  m << "| load | quantity | probe | coupled vs DE | coupled vs FE | between FE and DE |\n"
    << "|---|---|---|---|---|---|\n";
  char buf[256];
  for (const std::string load : {"tension", "bending"})
  {
    const auto& fe = runs.at("fe_" + load + "_dynamic");
    const auto& cp = runs.at("coupled_" + load + "_dynamic");
    const auto& de = runs.at("de_" + load + "_dynamic");
    for (const std::string probe : {"probe_0_75", "probe_0_4351"})
      for (const std::string q : {"first_frequency_hz", "amplitude_m"})
      {
        const double vf = fe.at(probe).at(q), vc = cp.at(probe).at(q), vd = de.at(probe).at(q);
        const bool between = (vc - vf) * (vc - vd) <= 0.0;
        table[load][probe][q] = {{"coupled_vs_de", rel(vc, vd)}, {"coupled_vs_fe", rel(vc, vf)},
                                 {"fe", vf}, {"coupled", vc}, {"de", vd}, {"between", between}};
        std::snprintf(buf, sizeof buf, "| %s | %s | %s | %+.2f %% | %+.2f %% | %s |\n", load.c_str(),
                      q == "amplitude_m" ? "amplitude" : "first frequency", probe.c_str(),
                      100.0 * rel(vc, vd), 100.0 * rel(vc, vf), between ? "yes" : "no");
        m << buf;
      }
  }
  m << "\n| load | model | static end displacement [m] | beam theory [m] | error |\n|---|---|---|---|---|\n";
  for (const std::string load : {"tension", "bending"})
    for (const std::string model : {"fe", "coupled", "de"})
    {
      const auto& r = runs.at(model + "_" + load + "_static");
      const double u = r.at("static_end_displacement_m"), ref = r.at("reference_end_displacement_m");
      table["static"][load][model] = {{"end_displacement_m", u}, {"reference_m", ref}, {"relative_error", rel(u, ref)}};
      std::snprintf(buf, sizeof buf, "| %s | %s | %.5e | %.5e | %+.2f %% |\n", load.c_str(), model.c_str(), u, ref,
                    100.0 * rel(u, ref));
      m << buf;
    }
  m << "\n| model | load | regime | particles | shell nodes | steps | wall [s] |\n|---|---|---|---|---|---|---|\n";
  for (const auto& [key, r] : runs.items())
  {
    std::snprintf(buf, sizeof buf, "| %s | %s | %s | %d | %d | %lld | %.1f |\n",
                  r.at("model").get<std::string>().c_str(), r.at("load").get<std::string>().c_str(),
                  r.at("regime").get<std::string>().c_str(), r.at("particles").get<int>(),
                  r.at("shell_nodes").get<int>(), r.at("steps").get<long long>(), r.at("wall_s").get<double>());
    m << buf;
    table["wall_s"][key] = r.at("wall_s");
  }
  for (const std::string load : {"tension", "bending"})
  {
    const double s = runs.at("de_" + load + "_dynamic").at("wall_s").get<double>()
                     / runs.at("coupled_" + load + "_dynamic").at("wall_s").get<double>();
    table["speedup_coupled_over_de"][load] = s;
    const auto& ct = runs.at("coupled_" + load + "_dynamic").at("step_time_s");
    const auto& dt = runs.at("de_" + load + "_dynamic").at("step_time_s");
    std::snprintf(buf, sizeof buf,
                  "\nDynamic %s: the coupled model runs %.2f x faster than the DE model (steps: coupled "
                  "%.1f s = spheres %.1f s + shell %.1f s + multipliers %.1f s; DE %.1f s).\n",
                  load.c_str(), s, ct.at("de").get<double>() + ct.at("fe").get<double>() + ct.at("multipliers").get<double>(),
                  ct.at("de").get<double>(), ct.at("fe").get<double>(), ct.at("multipliers").get<double>(),
                  dt.at("de").get<double>());
    m << buf;
  }
  md = m.str();
  return table;
}

nlohmann::json compare_cases(const BarConfig& c, const std::filesystem::path& root)
{
  nlohmann::json runs;
  for (const std::string regime : {"static", "dynamic"})
    for (const std::string load : {"tension", "bending"})
      for (const std::string model : {"fe", "coupled", "de"})
      {
        BarConfig k = c;
        k.model = model;
        k.load = load;
        k.regime = regime;
        const std::string key = model + "_" + load + "_" + regime;
        k.output = (root / key).string();
        std::cout << "# case " << key << " (seed " << c.seed << ")" << std::endl;
        runs[key] = run_bar(k);
        write_json(root / key / "summary.json", runs[key]);
      }
  std::string md;
  const auto table = compare_table(runs, md);
  std::cout << "\n" << md << std::endl;
  write_text(root / "comparison.md", md);
  nlohmann::json all = {{"table", table}, {"runs", runs}};
  write_json(root / "comparison.json", all);
  return all;
}

nlohmann::json seeds_table(const std::vector<unsigned>& seeds, const std::vector<nlohmann::json>& tables,
                           std::string& markdown)
{
  if (seeds.size() < 2 || tables.size() != seeds.size())
    throw std::runtime_error("seeds table: " + std::to_string(seeds.size()) + " seeds and "
                             + std::to_string(tables.size()) + " tables: needs at least two seeds, one table each");
  const double n = static_cast<double>(seeds.size());
  auto mean_sd = [n](const std::vector<double>& v)
  {
    const double m = std::accumulate(v.begin(), v.end(), 0.0) / n;
    double ss = 0.0;
    for (double x : v)
      ss += (x - m) * (x - m);
    return std::pair<double, double>{m, std::sqrt(ss / (n - 1.0))};
  };
  auto percents = [](const std::vector<double>& v)
  {
    std::string out;
    char b[32];
    for (std::size_t i = 0; i < v.size(); ++i)
    {
      std::snprintf(b, sizeof b, "%s%+.2f", i ? ", " : "", 100.0 * v[i]);
      out += b;
    }
    return out + " %";
  };
  nlohmann::json out;
  out["seeds"] = seeds;
  std::ostringstream m;
  char buf[64];
  m << "Seeds:";
  for (auto sd : seeds)
    m << " " << sd;
  m << "\n\n| load | quantity | probe | FE: mean (sd) | coupled: mean (sd) | DE: mean (sd) | coupled vs DE, per seed "
       "| coupled vs FE, per seed | between |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string load : {"tension", "bending"})
    for (const std::string probe : {"probe_0_75", "probe_0_4351"})
      for (const std::string q : {"first_frequency_hz", "amplitude_m"})
      {
        std::map<std::string, std::vector<double>> v;
        int between = 0;
        for (const auto& t : tables)
        {
          const auto& e = t.at(load).at(probe).at(q);
          for (const std::string model : {"fe", "coupled", "de"})
            v[model].push_back(e.at(model).get<double>());
          v["coupled_vs_de"].push_back(e.at("coupled_vs_de").get<double>());
          v["coupled_vs_fe"].push_back(e.at("coupled_vs_fe").get<double>());
          between += e.at("between").get<bool>() ? 1 : 0;
        }
        auto& o = out[load][probe][q];
        m << "| " << load << " | " << (q == "amplitude_m" ? "amplitude" : "first frequency") << " | " << probe
          << " | ";
        for (const std::string model : {"fe", "coupled", "de"})
        {
          const auto [mu, sd] = mean_sd(v[model]);
          o[model] = {{"values", v[model]}, {"mean", mu}, {"sd", sd}, {"relative_sd", sd / std::abs(mu)}};
          std::snprintf(buf, sizeof buf, q == "amplitude_m" ? "%.4e (%.2f %%) | " : "%.2f (%.2f %%) | ", mu,
                        100.0 * sd / std::abs(mu));
          m << buf;
        }
        o["coupled_vs_de"] = v["coupled_vs_de"];
        o["coupled_vs_fe"] = v["coupled_vs_fe"];
        o["between"] = between;
        // (per-seed lists grow with the seeds: streamed, not through a fixed buffer)
        m << percents(v["coupled_vs_de"]) << " | " << percents(v["coupled_vs_fe"]) << " | " << between << " of "
          << seeds.size() << " |\n";
      }
  m << "\n| load | model | static error against beam theory, per seed | mean (sd) |\n|---|---|---|---|\n";
  for (const std::string load : {"tension", "bending"})
    for (const std::string model : {"fe", "coupled", "de"})
    {
      std::vector<double> e;
      for (const auto& t : tables)
        e.push_back(t.at("static").at(load).at(model).at("relative_error").get<double>());
      const auto [mu, sd] = mean_sd(e);
      out["static"][load][model] = {{"relative_error", e}, {"mean", mu}, {"sd", sd}};
      std::snprintf(buf, sizeof buf, "%+.2f %% (%.2f %%) |\n", 100.0 * mu, 100.0 * sd);
      m << "| " << load << " | " << model << " | " << percents(e) << " | " << buf;
    }
  markdown = m.str();
  return out;
}

} // namespace dembridge::demo
