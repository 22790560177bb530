// The deflection at chosen points: peaks and the free vibration's period
// (deflection.h).
#include "deflection.h"

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

namespace dembridge::demo
{

DeflectionTrack::DeflectionTrack(std::vector<std::array<double, 2>> points, double free_from)
  : _points(std::move(points)), _free_from(free_from), _peak(_points.size(), 0.0), _peak_t(_points.size(), 0.0),
    _last(_points.size(), 0.0), _first(_points.size(), 0.0), _latest(_points.size(), 0.0),
    _crossings(_points.size(), 0.0)
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
    {
      _latest[q] = _t_last + (t - _t_last) * _last[q] / (_last[q] - w[q]);
      if (_crossings[q] == 0.0)
        _first[q] = _latest[q];
      _crossings[q] += 1.0;
    }
    _last[q] = w[q];
  }
  _t_last = t;
}

nlohmann::json DeflectionTrack::report() const
{
  auto out = nlohmann::json::array();
  for (std::size_t q = 0; q < _points.size(); ++q)
  {
    const double n = _crossings[q];
    nlohmann::json j = {{"x_m", _points[q][0]},  {"y_m", _points[q][1]},
                        {"peak_m", _peak[q]},    {"peak_time_s", _peak_t[q]},
                        {"zero_crossings", static_cast<std::int64_t>(n)}, {"period_s", nullptr}};
    if (n >= 3.0)
      j["period_s"] = 2.0 * (_latest[q] - _first[q]) / (n - 1.0);
    out.push_back(j);
  }
  return out;
}

void DeflectionTrack::save(const checkpoint::Group& g) const
{
  g.write("peak", _peak);
  g.write("peak_time", _peak_t);
  g.write("last", _last);
  g.write("time_last", _t_last);
  g.write("first_crossing", _first);
  g.write("latest_crossing", _latest);
  g.write("crossings", _crossings);
}

void DeflectionTrack::load(const checkpoint::Group& g)
{
  for (auto [name, v] : {std::pair{"peak", &_peak}, {"peak_time", &_peak_t}, {"last", &_last},
                         {"first_crossing", &_first}, {"latest_crossing", &_latest}, {"crossings", &_crossings}})
  {
    g.read(name, *v);
    if (v->size() != _points.size())
      g.fail(name, "not the " + std::to_string(_points.size()) + " deflection points' (file damaged?)");
  }
  _t_last = g.read_double("time_last");
}

} // namespace dembridge::demo
