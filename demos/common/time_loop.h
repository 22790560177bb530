#pragma once
/// @file time_loop.h
/// The time loop every program runs (docs/architecture.md, "The time
/// loop"). A program sets up its model, then hands the loop its step and
/// its measurements as hooks; the loop owns their order, the cadences of
/// history rows, frames and progress lines, the end conditions,
/// checkpoints and Ctrl-C. Per step k (1-based):
///
///     step(k); after_step(k); done = finished(k);
///     row, frame, progress (each on its cadence, and at the last step);
///     done ? end : checkpoint or stop check
///
/// "last" is true at the loop's final step: its step limit, or the step at
/// which `finished` first says true (then no checkpoint is written: the run
/// is over).

#include "restart.h"

#include <cstdint>
#include <functional>

namespace dembridge::demo
{

/// A cadence in steps: every `steps` steps (0: never on a cadence), and at
/// the loop's last step if `at_end`.
struct Every
{
  std::int64_t steps = 0;
  bool at_end = true;
};

struct LoopHooks
{
  /// Advances the state by step k. Required.
  std::function<void(std::int64_t k)> step;
  /// The physical time reached [s]. Required.
  std::function<double()> time;
  /// The program's measurements after step k, every step, before its end
  /// condition is asked. Empty: none.
  std::function<void(std::int64_t k)> after_step;
  /// The program's end condition, asked once before the first step (k =
  /// the steps already done; true: no step is run) and after every step.
  /// Empty: the loop runs to its step limit.
  std::function<bool(std::int64_t k)> finished;
  /// A history row, a frame and a progress line for step k, called on
  /// their cadences (LoopPlan). Each may be empty.
  std::function<void(std::int64_t k, bool last)> row, frame, progress;
  /// Writes the run's state into a checkpoint's root group (with a
  /// Checkpointer). Empty: checkpoints are not written.
  std::function<void(const checkpoint::Group&)> save;
};

struct LoopPlan
{
  std::int64_t done = 0; ///< steps already done (a restart continues from there)
  std::int64_t last = 0; ///< the step limit
  Every rows, frames, prints;
  /// Progress also every this many seconds of wall clock (0: by steps only).
  double print_seconds = 0.0;
  /// Checkpoints (restart.h); null: none, a stop request still ends the
  /// loop at the end of its step (check_stop).
  Checkpointer* checkpoints = nullptr;
};

struct LoopEnd
{
  std::int64_t steps = 0; ///< the steps done when the loop ended
  bool finished = false;  ///< ended by `finished` (else by the step limit)
};

/// How every run starts its loop: from its checkpoint (`resume`) when it
/// restarts, else with its output files opened (`open_output`).
inline void start_or_resume(const Checkpointer* checkpoints, const std::function<void()>& resume,
                            const std::function<void()>& open_output)
{
  if (checkpoints && checkpoints->restarting())
    resume();
  else
    open_output();
}

/// Hooks whose step and time are those of `solver` (anything with step()
/// and time(): dem::DemSolver, shell::ExplicitSolver), which must outlive
/// them; the others empty.
template <class Solver>
LoopHooks solver_hooks(Solver& solver)
{
  LoopHooks h;
  h.step = [&solver](std::int64_t) { solver.step(); };
  h.time = [&solver] { return solver.time(); };
  return h;
}

/// Runs steps plan.done + 1 ... plan.last (fewer if `finished`).
/// @throws Interrupted on a stop request (SIGINT, SIGTERM), after the
///   checkpoint it asks for.
LoopEnd run_time_loop(const LoopPlan& plan, const LoopHooks& hooks);

} // namespace dembridge::demo
