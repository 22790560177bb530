#pragma once
// Reading a checkpoint group back into arrays the run's set-up has sized
// (internal to dem: DemSolver's state and its bars).
#include "dembridge/core/checkpoint.h"

#include <string>
#include <vector>

namespace dembridge::dem::impl
{
using checkpoint::Group;

/// Reads `name` into v, which must keep its length (the run's set-up).
template <typename T> inline void read_same_size(const Group& g, const std::string& name, std::vector<T>& v)
{
  std::vector<T> r;
  g.read(name, r);
  if (r.size() != v.size())
    g.fail(name, "holds " + std::to_string(r.size()) + " values, this run has " + std::to_string(v.size())
                     + " (the checkpoint is of another set-up)");
  v = std::move(r);
}

/// Fails unless the stored `name` equals v: what the set-up fixes (radii,
/// link ends) identifies the assembly the checkpoint belongs to.
template <typename T> inline void check_same(const Group& g, const std::string& name, const std::vector<T>& v)
{
  std::vector<T> r;
  g.read(name, r);
  if (r != v)
    g.fail(name, "differs from this run's (the checkpoint is of another assembly: restart with the "
                 "options of the run that wrote it)");
}

} // namespace dembridge::dem::impl
