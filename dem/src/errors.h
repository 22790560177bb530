#pragma once
// Internal to dem/: the error message for a value out of its allowed range.
#include <sstream>
#include <stdexcept>
#include <string>

namespace dembridge::dem::impl
{
/// Throws std::runtime_error "what = v: must be allowed".
[[noreturn]] inline void out_of_range(const std::string& what, double v, const std::string& allowed)
{
  std::ostringstream s;
  s << what << " = " << v << ": must be " << allowed;
  throw std::runtime_error(s.str());
}
} // namespace dembridge::dem::impl
