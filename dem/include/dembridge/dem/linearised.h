#pragma once
/// @file linearised.h
/// The linearised stiffness of the links as an operator applied over the
/// threads, for the power iterations of the critical steps (forces.h:
/// stiffness_action, particle_critical_time_step; bridge's coupled step).

#include "dembridge/dem/assembly.h"

#include <cstdint>
#include <span>
#include <vector>

namespace dembridge::dem
{

/// f = K u of the intact links about the current positions (the action
/// forces.h's stiffness_action describes), for the links as they are at
/// construction: the spheres and links must outlive it, unchanged. Each
/// link writes its forces into its own slots, then each sphere sums its
/// links' slots in link order, as a serial loop over the links would: f is
/// the same to the last bit whatever the thread count.
class StiffnessOperator
{
public:
  StiffnessOperator(const Particles& p, const Links& l);
  /// u and f: 6 values per particle, translations (n, 3) then rotations (n, 3).
  /// @throws std::runtime_error if u or f is not sized so
  void apply(std::span<const double> u, std::span<double> f);

private:
  const Particles& _p;
  const Links& _l;
  std::vector<std::int32_t> _first, _links; ///< per sphere, its intact links in order (CSR)
  std::vector<double> _out;                 ///< per link: force on a (3), torques on a (3) and b (3)
};

} // namespace dembridge::dem
