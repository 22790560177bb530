// What the impact demo builds from a scenario (scenario.h): the
// projectile's shape and path, the packing's size scale along the path,
// and the reinforcement's bars.
#include "scenario.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace dembridge::demo
{

dem::Shape projectile_shape(const ProjectileSpec& q)
{
  dem::Shape sh;
  sh.kind = dem::Shape::Kind::projectile;
  sh.diameter = q.diameter;
  sh.length = q.length;
  sh.nose = q.nose == "flat" ? dem::Nose::flat
            : q.nose == "hemispherical" ? dem::Nose::hemispherical
            : q.nose == "conical" ? dem::Nose::conical
                                 : dem::Nose::ogive;
  sh.crh = q.crh;
  sh.cone_angle_deg = q.cone_angle_deg;
  try
  {
    sh.validate();
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(std::string("projectile: ") + e.what() + " (projectile.length_m, diameter_m, crh, "
                             "cone_angle_deg)");
  }
  return sh;
}

std::array<double, 3> path_direction(const ProjectileSpec& q)
{
  const double th = q.obliquity_deg * std::numbers::pi / 180.0;
  return {std::sin(th), 0.0, -std::cos(th)};
}

std::function<double(const dem::Point&)> fine_scale(const Scenario& s)
{
  const TargetSpec& t = s.target;
  const ProjectileSpec& q = s.projectile;
  const std::array<double, 3> dir = path_direction(q), aim{q.aim[0], q.aim[1], 0.0};
  const double R = t.fine_radius, w = t.transition(), fine = t.fine_mean() / t.mean_radius;
  return [=](const dem::Point& x)
  {
    const double v[3] = {x[0] - aim[0], x[1] - aim[1], x[2] - aim[2]};
    const double a = v[0] * dir[0] + v[1] * dir[1] + v[2] * dir[2];
    const double u[3] = {v[0] - a * dir[0], v[1] - a * dir[1], v[2] - a * dir[2]};
    const double d = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    return fine + (1.0 - fine) * std::clamp((d - R) / w, 0.0, 1.0);
  };
}

std::vector<dem::BarLine> mat_lines(const Scenario& s)
{
  const ReinforcementSpec& b = s.reinforcement;
  const TargetSpec& t = s.target;
  const std::string at = "scenario " + s.file.string() + ": reinforcement.";
  std::vector<dem::BarLine> lines;
  const double d = b.bar_diameter, cover = b.cover > 0.0 ? b.cover : 2.0 * d;
  if (b.layers > 0)
  {
    if (cover < 0.5 * d)
      throw std::runtime_error(at + "cover_m = " + number_text(cover) + ": allowed >= the bar radius "
                               + number_text(0.5 * d) + " m (the bars inside the slab)");
    for (int k = 0; k < 2; ++k)
      if (!(b.spacing[k] > d))
        throw std::runtime_error(at + "spacing_m = [" + number_text(b.spacing[0]) + ", " + number_text(b.spacing[1])
                                 + "]: each allowed > the bar diameter " + number_text(d) + " m (bars apart)");
    // a mat: bars along x on top of bars along y, their axes 1.001 d apart;
    // the outermost axes `cover` from the faces
    const double gap = 1.001 * d;
    const double top = -cover - 0.5 * gap, bottom = -t.thickness + cover + 0.5 * gap;
    // adjacent mats' centres at least 2 gaps apart (the lower mat's top bars
    // one diameter below the upper mat's bottom ones)
    if (b.layers > 1 && (top - bottom) / (b.layers - 1) < 2.0 * gap)
      throw std::runtime_error(at + "layers = " + std::to_string(b.layers) + ": the mats (" + number_text(2 * gap)
                               + " m apart at least) do not fit between the covers (cover_m " + number_text(cover)
                               + " m) in the thickness " + number_text(t.thickness) + " m");
    if (b.layers == 1 && bottom + 0.5 * gap + 0.5 * d > 0.0)
      throw std::runtime_error(at + "cover_m = " + number_text(cover) + ": the mat does not fit in the thickness "
                               + number_text(t.thickness) + " m");
    for (int m = 0; m < b.layers; ++m)
    {
      const double zc = b.layers == 1 ? bottom : top - (top - bottom) * m / (b.layers - 1);
      for (int dir = 0; dir < 2; ++dir)
      {
        // bars along x (dir 0) lie across y, spaced spacing[0]
        const double across = t.size[1 - dir], s_k = b.spacing[dir];
        const int n = static_cast<int>(std::floor((across - 2.0 * cover) / s_k + 1e-9)) + 1;
        const double z = zc + (dir == 0 ? 0.5 : -0.5) * gap;
        for (int k = 0; k < n; ++k)
        {
          const double c = (k - 0.5 * (n - 1)) * s_k;
          const double half = 0.5 * t.size[dir];
          dem::BarLine line;
          line.diameter = d;
          line.points = dir == 0 ? std::vector<std::array<double, 3>>{{-half, c, z}, {half, c, z}}
                                 : std::vector<std::array<double, 3>>{{c, -half, z}, {c, half, z}};
          lines.push_back(line);
        }
      }
    }
  }
  return lines;
}

std::vector<dem::BarLine> bar_lines(const Scenario& s)
{
  const ReinforcementSpec& b = s.reinforcement;
  const TargetSpec& t = s.target;
  const std::string at = "scenario " + s.file.string() + ": reinforcement.";
  if (!b.any())
    return {};
  std::vector<dem::BarLine> lines = mat_lines(s);
  for (std::size_t q = 0; q < b.polylines.size(); ++q)
  {
    dem::BarLine line;
    line.diameter = b.bar_diameter;
    line.points = b.polylines[q];
    // some part inside the slab (bars may leave it through its faces)
    bool inside = false;
    for (std::size_t k = 1; k < line.points.size() && !inside; ++k)
      for (int j = 0; j <= 100 && !inside; ++j)
      {
        const double u = j / 100.0;
        const auto& a = line.points[k - 1];
        const auto& c = line.points[k];
        const double x = a[0] + u * (c[0] - a[0]), y = a[1] + u * (c[1] - a[1]), z = a[2] + u * (c[2] - a[2]);
        inside = std::abs(x) < 0.5 * t.size[0] && std::abs(y) < 0.5 * t.size[1] && z < 0.0 && z > -t.thickness;
      }
    if (!inside)
      throw std::runtime_error(at + "bars_m: bar " + std::to_string(q) + " lies outside the target (the slab is x, y "
                               "in [-size/2, size/2], z in [-thickness, 0])");
    lines.push_back(line);
  }
  return lines;
}

} // namespace dembridge::demo
