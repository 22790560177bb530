#pragma once
/// @file cantilever.h
/// The cantilever experiment of demos/shell_cantilever, as a function the
/// demo and the tests share: a bar clamped at local x = 0, modelled by shells
/// (mid-surface length x width, thickness h) or by solids (length x width x h),
/// in free axial or bending vibration from its first mode shape, or under a
/// static tip load (damped explicit run and/or direct solve).

#include "dembridge/shell/mesh.h"
#include "dembridge/shell/model.h"

#include "restart.h"

#include <nlohmann/json.hpp>
#include <string>

namespace dembridge::demo
{

struct CantileverConfig
{
  std::string load = "bending";        ///< axial | bending | static-tip
  std::string cell = "quadrilateral";  ///< triangle | quadrilateral (shell), hexahedron | tetrahedron (solid)
  int nx = 68, ny = 20, nz = 8;        ///< divisions along length, width, thickness (solids)
  double length = 0.85;                ///< [m]
  double width = 0.25;                 ///< [m]
  shell::Material material;            ///< E, nu, rho, thickness, shear factor, drilling
  double tip_load = 1e5;               ///< [N], along local z (static-tip)
  double amplitude = 1e-4;             ///< initial modal tip amplitude [m] (dynamic)
  /// Initial shape (dynamic): "mode" = beam mode shape refined by inverse
  /// iteration to the FE model's own first mode; "analytic" = the beam mode
  /// shape as is; "static" = the static shape under a tip load.
  std::string initial = "mode";
  double periods = 5.0;                ///< run length in reference periods if end_time = 0
  double end_time = 0.0;               ///< [s]; 0 = automatic
  double dt = 0.0;                     ///< [s]; 0 = safety * critical
  double safety = 0.9;                 ///< fraction of the critical time step
  double damping = -1.0;               ///< [1/s]; < 0 = automatic (0 dynamic, 2 omega_1 static)
  std::string solver = "both";         ///< static-tip: explicit | direct | both
  std::string force_method = "matmult";///< matmult | residual
  std::string mesh_file;               ///< XDMF mesh instead of the structured one
  shell::Placement placement;          ///< where the bar sits in space
  std::string output_dir;              ///< "" = write nothing
  int frames = 50;                     ///< XDMF frames over the run
  bool quiet = false;                  ///< no progress lines
  /// Checkpoints and restart (restart.h); null: neither.
  const RestartOptions* restart = nullptr;
};

/// Runs the experiment; returns the summary (keys:
/// first_frequency_hz, reference_frequency_hz, tip_deflection_m,
/// reference_deflection_m, relative_error, dt_s, steps, wall_s, and more).
/// @throws std::runtime_error on bad input.
nlohmann::json run_cantilever(const CantileverConfig& cfg);

} // namespace dembridge::demo
