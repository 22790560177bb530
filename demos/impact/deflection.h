#pragma once
/// @file deflection.h
/// The slab's deflection at chosen points (shells.deflection_points_m),
/// followed every step: its largest value and, once a pulse is over, the
/// period of the free vibration from the times the deflection crosses
/// zero (docs/impact.md, "Elastic checks"). Shared by the three models.

#include "dembridge/core/checkpoint.h"

#include <array>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

namespace dembridge::demo
{

class DeflectionTrack
{
public:
  /// `points` followed; zero crossings counted after time `free_from` [s]
  /// (the pulse's end: the slab then vibrates freely about u = 0).
  DeflectionTrack(std::vector<std::array<double, 2>> points, double free_from);

  /// The deflections w [m] (one per point) at time t [s].
  void add(double t, std::span<const double> w);

  /// Per point: x_m, y_m, peak_m (the deflection of largest magnitude,
  /// signed), peak_time_s, and period_s (2 (t_last - t_first) / (n - 1)
  /// over the n zero crossings after free_from; null for fewer than 3).
  nlohmann::json report() const;

  void save(const checkpoint::Group& g) const;
  void load(const checkpoint::Group& g);

private:
  std::vector<std::array<double, 2>> _points;
  double _free_from;
  std::vector<double> _peak, _peak_t, _last;
  double _t_last = -1.0;
  // the zero crossings after free_from: the first's and the last's times,
  // and their number (all the period needs)
  std::vector<double> _first, _latest, _crossings;
};

} // namespace dembridge::demo
