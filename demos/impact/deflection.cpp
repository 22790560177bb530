// The deflection at chosen points: peaks and the free vibration's period
// (deflection.h).
#include "deflection.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace dembridge::demo
{

DeflectionTrack::DeflectionTrack(std::vector<std::array<double, 2>> points, double free_from)
  : _points(std::move(points)), _free_from(free_from), _peak(_points.size(), 0.0), _peak_t(_points.size(), 0.0),
    _last(_points.size(), 0.0), _crossings(_points.size())
{
}

void DeflectionTrack::add(double t, std::span<const double> w)
{
  for (std::size_t q = 0; q < _points.size(); ++q)
  {
    if (std::abs(w[q]) > std::abs(_peak[q]))
    {
      _peak[q] = w[q];
      _peak_t[q] = t;
    }
    // a sign change between the last sample and this one: the crossing's
    // time by linear interpolation
    if (_t_last >= _free_from && ((_last[q] < 0.0 && w[q] >= 0.0) || (_last[q] > 0.0 && w[q] <= 0.0)))
      _crossings[q].push_back(_t_last + (t - _t_last) * _last[q] / (_last[q] - w[q]));
    _last[q] = w[q];
  }
  _t_last = t;
}

nlohmann::json DeflectionTrack::report() const
{
  auto out = nlohmann::json::array();
  for (std::size_t q = 0; q < _points.size(); ++q)
  {
    const auto& c = _crossings[q];
    nlohmann::json j = {{"x_m", _points[q][0]}, {"y_m", _points[q][1]}, {"peak_m", _peak[q]},
                        {"peak_time_s", _peak_t[q]}, {"zero_crossings", c.size()}, {"period_s", nullptr}};
    if (c.size() >= 3)
      j["period_s"] = 2.0 * (c.back() - c.front()) / static_cast<double>(c.size() - 1);
    out.push_back(j);
  }
  return out;
}

void DeflectionTrack::save(const checkpoint::Group& g) const
{
  std::vector<double> flat, counts;
  for (const auto& c : _crossings)
  {
    counts.push_back(static_cast<double>(c.size()));
    flat.insert(flat.end(), c.begin(), c.end());
  }
  g.write("peak", _peak);
  g.write("peak_time", _peak_t);
  g.write("last", _last);
  g.write("time_last", _t_last);
  g.write("crossing_counts", counts);
  g.write("crossings", flat);
}

void DeflectionTrack::load(const checkpoint::Group& g)
{
  std::vector<double> flat, counts;
  g.read("peak", _peak);
  g.read("peak_time", _peak_t);
  g.read("last", _last);
  g.read("crossing_counts", counts);
  g.read("crossings", flat);
  if (_peak.size() != _points.size() || _peak_t.size() != _points.size() || _last.size() != _points.size()
      || counts.size() != _points.size())
    g.fail("peak", "not the " + std::to_string(_points.size()) + " deflection points' (file damaged?)");
  _t_last = g.read_double("time_last");
  std::size_t at = 0;
  for (std::size_t q = 0; q < counts.size(); ++q)
  {
    const auto n = static_cast<std::size_t>(counts[q]);
    if (at + n > flat.size())
      g.fail("crossings", "fewer values than the counts say (file damaged?)");
    _crossings[q].assign(flat.begin() + at, flat.begin() + at + n);
    at += n;
  }
  if (at != flat.size())
    g.fail("crossings", "more values than the counts say (file damaged?)");
}

} // namespace dembridge::demo
