// The shared time loop (demos/common/time_loop.h): the order of the hooks,
// the cadences and the end conditions, on a loop that only records what it
// is called with.
#include "time_loop.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <string>
#include <vector>

using namespace dembridge::demo;

namespace
{
/// Hooks that log each call as "hook k" (and "!" for a last step).
struct Log
{
  std::vector<std::string> calls;
  std::int64_t finish_at = -1; // finished(k) is true from this step on
  LoopHooks hooks()
  {
    LoopHooks h;
    auto note = [this](const char* what, std::int64_t k, bool last = false)
    { calls.push_back(std::string(what) + " " + std::to_string(k) + (last ? "!" : "")); };
    h.step = [=](std::int64_t k) { note("step", k); };
    h.time = [] { return 0.0; };
    h.after_step = [=](std::int64_t k) { note("after", k); };
    h.finished = [=, this](std::int64_t k) { return finish_at >= 0 && k >= finish_at; };
    h.row = [=](std::int64_t k, bool last) { note("row", k, last); };
    h.frame = [=](std::int64_t k, bool last) { note("frame", k, last); };
    h.progress = [=](std::int64_t k, bool last) { note("progress", k, last); };
    return h;
  }
  std::vector<std::string> of(const std::string& what) const
  {
    std::vector<std::string> out;
    for (const auto& c : calls)
      if (c.rfind(what + " ", 0) == 0)
        out.push_back(c);
    return out;
  }
};
} // namespace

TEST_CASE("time loop: hooks in order, cadences, and the last step", "[loop]")
{
  Log log;
  LoopPlan plan;
  plan.last = 10;
  plan.rows = {3, true};
  plan.frames = {4, false};
  plan.prints = {5, true};
  const LoopEnd end = run_time_loop(plan, log.hooks());
  CHECK(end.steps == 10);
  CHECK_FALSE(end.finished);
  using V = std::vector<std::string>;
  CHECK(log.of("step").size() == 10);
  CHECK(log.of("row") == V{"row 3", "row 6", "row 9", "row 10!"});
  CHECK(log.of("frame") == V{"frame 4", "frame 8"});
  CHECK(log.of("progress") == V{"progress 5", "progress 10!"});
  // one step's order: step, measurements, then the outputs
  CHECK(std::vector<std::string>(log.calls.begin(), log.calls.begin() + 2) == V{"step 1", "after 1"});
  const auto at = std::find(log.calls.begin(), log.calls.end(), "step 6") - log.calls.begin();
  CHECK(std::vector<std::string>(log.calls.begin() + at, log.calls.begin() + at + 3) == V{"step 6", "after 6", "row 6"});
}

TEST_CASE("time loop: the end condition ends it, also before the first step", "[loop]")
{
  using V = std::vector<std::string>;
  Log log;
  log.finish_at = 5;
  LoopPlan plan;
  plan.last = 100;
  plan.rows = {3, true};
  LoopEnd end = run_time_loop(plan, log.hooks());
  CHECK(end.steps == 5);
  CHECK(end.finished);
  CHECK(log.of("row") == V{"row 3", "row 5!"});
  CHECK(log.of("step").back() == "step 5");
  // a run continued from step 7, already past its end: no step
  Log done;
  done.finish_at = 5;
  plan.done = 7;
  end = run_time_loop(plan, done.hooks());
  CHECK(end.steps == 7);
  CHECK(end.finished);
  CHECK(done.calls.empty());
  // continued from step 8 of 10: steps 9 and 10 only
  Log rest;
  plan.done = 8;
  plan.last = 10;
  end = run_time_loop(plan, rest.hooks());
  CHECK(rest.of("step") == V{"step 9", "step 10"});
  CHECK(rest.of("row") == V{"row 9", "row 10!"});
}

TEST_CASE("time loop: a wall-clock progress prints at the first step", "[loop]")
{
  Log log;
  LoopPlan plan;
  plan.last = 3;
  plan.prints.at_end = false;
  plan.print_seconds = 1e6;
  run_time_loop(plan, log.hooks());
  CHECK(log.of("progress") == std::vector<std::string>{"progress 1"});
}

TEST_CASE("time loop: the step and time hooks are required", "[loop][errors]")
{
  LoopPlan plan;
  plan.last = 1;
  LoopHooks h;
  CHECK_THROWS_AS(run_time_loop(plan, h), std::logic_error);
}
