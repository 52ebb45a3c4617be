// The CLI's text for a frame's stats: the stage times, and a note where the blend's time held
// more than the blend (the CUDA bin sort's per-bin blocks running beside it).
#include <gtest/gtest.h>

#include <string>

#include "flashgs/stats.h"
#include "stats_format.h"

namespace flashgs {
namespace {

FrameStats stats_with_times(bool sort_in_blend) {
  FrameStats s;
  s.times.project_ms = 0.074;
  s.times.sort_ms = 0.023;
  s.times.ranges_ms = 0.001;
  s.times.blend_ms = 0.220;
  s.times.total_ms = 0.318;
  s.times.sort_in_blend = sort_in_blend;
  return s;
}

TEST(StatsFormat, PrintsEachStageTime) {
  const std::string text = cli::format_stats(stats_with_times(false));
  EXPECT_NE(text.find("project 0.074"), std::string::npos) << text;
  EXPECT_NE(text.find("sort 0.023"), std::string::npos) << text;
  EXPECT_NE(text.find("blend 0.220"), std::string::npos) << text;
  EXPECT_NE(text.find("total 0.318"), std::string::npos) << text;
}

TEST(StatsFormat, SaysWhenTheBlendTimeHoldsTheBinSortBlocks) {
  const std::string plain = cli::format_stats(stats_with_times(false));
  const std::string overlapped = cli::format_stats(stats_with_times(true));
  const std::string note = blend_time_note(stats_with_times(true).times);
  ASSERT_FALSE(note.empty());
  EXPECT_EQ(std::string(blend_time_note(stats_with_times(false).times)), "");
  EXPECT_EQ(plain.find(note), std::string::npos) << plain;
  EXPECT_NE(overlapped.find(note), std::string::npos) << overlapped;
}

}  // namespace
}  // namespace flashgs
