// The scripted-run driver without a window: which frames are timed, when --then-open and the end come, the camera path's time, the report.
#include <gtest/gtest.h>

#include "flashgs/error.h"
#include "scripted_run.h"

namespace fv = flashgs::viewer;

namespace {

fv::FrameTimes times_of(double ms) {
  fv::FrameTimes t;
  t.frame_ms = ms;
  t.render_call_ms = ms / 2;
  return t;
}

}  // namespace

TEST(ViewerScriptedRun, FrameZeroIsNotTimedAndTheRunEndsAfterItsFrames) {
  fv::ScriptedRunPlan plan;
  plan.frames = 3;
  plan.then_open = true;
  fv::ScriptedRun run(plan);
  EXPECT_FALSE(run.timed_any());
  run.frame_presented(times_of(1000));  // setup
  EXPECT_TRUE(run.open_then_now()) << "--then-open after the first frame";
  EXPECT_FALSE(run.done());
  run.frame_presented(times_of(10));
  EXPECT_FALSE(run.open_then_now());
  EXPECT_FALSE(run.done());
  run.frame_presented(times_of(20));
  EXPECT_TRUE(run.done());
  EXPECT_EQ(run.frames_report(64, 36, "test path").rfind("viewer frames: 2 at 64x36 on test path | mean 15.000 ms", 0), 0u)
      << run.frames_report(64, 36, "test path");
  EXPECT_NE(run.split_report().find("render call 7.500"), std::string::npos) << run.split_report();
}

TEST(ViewerScriptedRun, PathRunsWarmUpThenSweepThePath) {
  fv::ScriptedRunPlan plan;
  plan.path = true;
  plan.frames = 4;
  plan.warmup = 2;
  fv::ScriptedRun run(plan);
  std::vector<double> t;
  while (!run.done()) {
    t.push_back(run.path_time());
    run.frame_presented(times_of(5));
  }
  EXPECT_EQ(t, std::vector<double>({0.0, 0.0, 0.0, 0.25, 0.5, 0.75}));
  EXPECT_EQ(run.frames_report(1, 1, "p").rfind("viewer frames: 4 at", 0), 0u) << "the warm-up frames are not timed";
  fv::ScriptedRunPlan no_count;
  no_count.path = true;
  no_count.warmup = 0;
  fv::ScriptedRun default_length(no_count);
  int frames = 0;
  for (; !default_length.done(); ++frames) default_length.frame_presented(times_of(1));
  EXPECT_EQ(frames, 120) << "a path run without --frames: 120 frames";
}

TEST(ViewerScriptedRun, TheKeyScriptIsTheInputUntilItEndsAndKeepsTheRunGoing) {
  fv::ScriptedRunPlan plan;
  plan.keys = "W:0.05";  // 3 frames at 1/60 s
  fv::ScriptedRun run(plan);
  int held = 0;
  while (run.has_input()) {
    held += run.next_input().nav.forward;
    run.frame_presented(times_of(1));
    if (run.has_input()) {
      EXPECT_FALSE(run.done());
    }
  }
  EXPECT_EQ(held, 3);
  EXPECT_TRUE(run.done());
  EXPECT_THROW(fv::ScriptedRun(fv::ScriptedRunPlan{"W:x"}), flashgs::Error);
}
