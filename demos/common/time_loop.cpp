#include "time_loop.h"

#include "support.h"

#include <stdexcept>

namespace dembridge::demo
{

namespace
{
bool due(const Every& e, std::int64_t k, bool last)
{
  return (e.steps > 0 && k % e.steps == 0) || (last && e.at_end);
}
} // namespace

LoopEnd run_time_loop(const LoopPlan& plan, const LoopHooks& hooks)
{
  if (!hooks.step || !hooks.time)
    throw std::logic_error("run_time_loop: the step and time hooks are required");
  const Stopwatch clock;
  double printed = -1e300; // a wall-clock cadence prints at the first step
  LoopEnd end{plan.done, hooks.finished && hooks.finished(plan.done)};
  for (std::int64_t k = plan.done + 1; k <= plan.last && !end.finished; ++k)
  {
    hooks.step(k);
    end.steps = k;
    if (hooks.after_step)
      hooks.after_step(k);
    end.finished = hooks.finished && hooks.finished(k);
    const bool last = end.finished || k == plan.last;
    if (hooks.row && due(plan.rows, k, last))
      hooks.row(k, last);
    if (hooks.frame && due(plan.frames, k, last))
      hooks.frame(k, last);
    if (hooks.progress
        && (due(plan.prints, k, last) || (plan.print_seconds > 0.0 && clock.seconds() - printed > plan.print_seconds)))
    {
      hooks.progress(k, last);
      printed = clock.seconds();
    }
    if (end.finished)
      break;
    if (plan.checkpoints && hooks.save)
      plan.checkpoints->end_of_step(k, hooks.time(), hooks.save);
    else
      check_stop(hooks.time());
  }
  return end;
}

} // namespace dembridge::demo
