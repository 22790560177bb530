#pragma once
/// @file text.h
/// A number as messages write it: as std::ostream gives it (6 significant
/// digits, "0.03", "1e-12"), for errors that name the value.

#include <sstream>
#include <string>

namespace dembridge::core
{
inline std::string number_text(double v)
{
  std::ostringstream s;
  s << v;
  return s.str();
}
} // namespace dembridge::core
