// The library's checks of user-typed values: the WxH parser, the frame memory estimate,
// image comparison and look-at cameras on bad input.
#include <gtest/gtest.h>

#include <string>

#include "flashgs/error.h"
#include "flashgs/frame_memory.h"
#include "flashgs/generators.h"
#include "flashgs/image.h"
#include "flashgs/parse.h"

namespace flashgs {
namespace {

TEST(ParseResolution, AcceptsWxH) {
  const Resolution r = parse_resolution("1920x1080");
  EXPECT_EQ(r.width, 1920);
  EXPECT_EQ(r.height, 1080);
  EXPECT_EQ(parse_resolution("7X5").width, 7);
  EXPECT_EQ(parse_resolution("65536x65536").height, 65536);
  EXPECT_EQ(parse_resolution("300x200", 300).width, 300);
}

TEST(ParseResolution, RejectsAnythingElseWithOneMessage) {
  // 4294967312 = 2^32 + 16 (sscanf's %d wrapped it to 16); 99999999999999999999 overflows 64 bits.
  for (const char* text : {"4294967312x9", "9x4294967312", "99999999999999999999x1", "65537x1", "0x5", "5x0",
                           "-1x5", "+5x5", "5x", "x5", "5", "", "5x5x", "5x5 ", " 5x5", "5*5", "5.0x5", "0x10x5"}) {
    try {
      parse_resolution(text);
      ADD_FAILURE() << "accepted \"" << text << "\"";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()),
                std::string("resolution \"") + text + "\": expected WxH with 1 <= W, H <= 65536");
    }
  }
  EXPECT_THROW(parse_resolution("301x200", 300), Error);
}

TEST(FrameMemory, GrowsWithPixelsPairsAndThreads) {
  const FrameMemory small = estimate_frame_memory(BackendKind::cpu, 1000, 640, 360, 1000, 4);
  EXPECT_EQ(small.image, 640u * 360u * 3u * sizeof(float));
  EXPECT_EQ(small.host, small.image + small.per_gaussian + small.per_tile + small.pairs);
  EXPECT_EQ(small.device, 0u);
  const FrameMemory more_pairs = estimate_frame_memory(BackendKind::cpu, 1000, 640, 360, 2000, 4);
  EXPECT_EQ(more_pairs.pairs, 2 * small.pairs);
  EXPECT_GT(estimate_frame_memory(BackendKind::cpu, 1000, 640, 360, 1000, 8).per_tile, small.per_tile);
  // 65536^2 does not overflow: 51.5 GB of float RGB.
  EXPECT_EQ(estimate_frame_memory(BackendKind::cpu, 1, 65536, 65536, 1, 1).image, 65536ull * 65536ull * 12ull);
  const FrameMemory gpu = estimate_frame_memory(BackendKind::cuda, 1000, 640, 360, 1000, 4);
  EXPECT_EQ(gpu.host, gpu.image);
  EXPECT_GT(gpu.device, gpu.image);
}

TEST(FrameMemory, ShortfallNamesTheFrameAndBothFigures) {
  const FrameMemory need = estimate_frame_memory(BackendKind::cpu, 30000, 51200, 28800, 30000, 2);
  AvailableMemory available{4000000000ull, "the address-space limit, RLIMIT_AS"};
  const std::string text = frame_memory_shortfall(need, 51200, 28800, available);
  EXPECT_EQ(text.rfind("a 51200x28800 frame needs about 18.", 0), 0u) << text;
  EXPECT_NE(text.find("image 17.7 GB"), std::string::npos) << text;
  EXPECT_NE(text.find("but 4.0 GB is available (the address-space limit, RLIMIT_AS)"), std::string::npos) << text;
  available.bytes = need.host;
  EXPECT_EQ(frame_memory_shortfall(need, 51200, 28800, available), "");
  EXPECT_EQ(frame_memory_shortfall(need, 51200, 28800, AvailableMemory{}), "");  // unknown: no refusal
}

TEST(FrameMemory, AvailableMemoryIsReadFromTheSystem) {
  const AvailableMemory available = available_host_memory();
  EXPECT_FALSE(available.limited_by.empty());  // Linux: /proc/meminfo at least
  EXPECT_GT(available.bytes, 0u);
}

TEST(CompareImages, SizeMismatchIsAFlashgsError) {
  Image a, b;
  a.resize(4, 3);
  b.resize(3, 4);
  EXPECT_THROW(compare_images(a, b), Error);
}

TEST(LookAtCamera, EyeAtTheTargetIsAnError) {
  const float eye[3] = {1, 2, 3}, up[3] = {0, -1, 0};
  EXPECT_THROW(look_at_camera(eye, eye, up, 64, 36, 60.0f), Error);
}

}  // namespace
}  // namespace flashgs
