// The viewer's settings file: a round trip keeps every value, a corrupt, unreadable or unwritable file is one line and the defaults.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "settings_store.h"

namespace fv = flashgs::viewer;

namespace {

std::string scratch(const std::string& name) {
  const std::string dir = std::string(FLASHGS_TEST_OUTPUT_DIR) + "/viewer_settings/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

void write_text(const std::string& path, const std::string& text) {
  FILE* f = std::fopen(path.c_str(), "w");
  ASSERT_TRUE(f);
  std::fputs(text.c_str(), f);
  std::fclose(f);
}

}  // namespace

TEST(ViewerSettingsStore, ARoundTripKeepsEveryValue) {
  const std::string path = scratch("round_trip") + "/sub/settings.ini";  // the folder is created
  fv::StoredSettings a;
  a.backend = "cpu";
  fv::switch_algorithm(a.settings.options, flashgs::Algorithm::baseline);
  a.settings.options.tight_bbox = false;
  a.settings.options.tau = 0.01f;
  a.settings.options.background[1] = 0.5f;
  a.settings.options.fp16_sh = true;  // not the default: lost if the store left it out
  a.settings.options.fp16_shape = true;
  a.settings.options.fp16_blend = true;
  a.settings.mode = fv::NavigationMode::orbit;
  a.settings.render_scale = 0.5f;
  a.settings.move_speed = 2.5f;
  fv::add_recent_file(a.recent, "/scenes/b");
  fv::add_recent_file(a.recent, "/scenes/a b.ply");
  ASSERT_EQ(fv::write_settings_file(path, a), "");
  fv::StoredSettings b;
  ASSERT_EQ(fv::read_settings_file(path, b), "");
  EXPECT_EQ(b.backend, "cpu");
  EXPECT_TRUE(b.settings.options == a.settings.options);
  EXPECT_EQ(b.settings.mode, fv::NavigationMode::orbit);
  EXPECT_FLOAT_EQ(b.settings.render_scale, 0.5f);
  EXPECT_FLOAT_EQ(b.settings.move_speed, 2.5f);
  EXPECT_EQ(b.recent, std::vector<std::string>({"/scenes/a b.ply", "/scenes/b"}));
}

TEST(ViewerSettingsStore, AMissingFileIsTheFirstRun) {
  fv::StoredSettings s;
  EXPECT_EQ(fv::read_settings_file(scratch("missing") + "/settings.ini", s), "");
  EXPECT_EQ(s.backend, "auto");
}

TEST(ViewerSettingsStore, ACorruptFileIsOneLineAndTheDefaults) {
  const std::string path = scratch("corrupt") + "/settings.ini";
  const std::pair<std::string, const char*> cases[] = {
      {"render_scale = 0.5\nrender_scale = banana\n", "line 2"},
      {"render_scale = nan\n", "line 1"},
      {"render_scale = 40\n", "line 1"},   // out of its range
      {"no equals sign\n", "line 1"},
      {"unknown_key = 1\n", "line 1"},
      {"background = 0,0\n", "line 1"},
      {"\x01\x02\xff garbage\n", "line 1"}};
  for (const auto& [text, where] : cases) {
    write_text(path, text);
    fv::StoredSettings s;
    const std::string problem = fv::read_settings_file(path, s);
    EXPECT_EQ(problem.rfind(path + " " + where + ": ", 0), 0u) << text << " -> " << problem;
    EXPECT_NE(problem.find("ignored, using the defaults"), std::string::npos) << problem;
    EXPECT_EQ(problem.find('\n'), std::string::npos) << "one line";
    EXPECT_FLOAT_EQ(s.settings.render_scale, 1.0f) << "nothing of a corrupt file is used: " << text;
  }
}

TEST(ViewerSettingsStore, AFolderOrUnwritablePlaceIsOneLine) {
  const std::string dir = scratch("unwritable");
  fv::StoredSettings s;
  const std::string problem = fv::read_settings_file(dir, s);  // a folder where the file should be
  EXPECT_EQ(problem, dir + ": is a folder, not a file: ignored, using the defaults");
  const std::string blocked = dir + "/a_file";
  write_text(blocked, "x");
  const std::string written = fv::write_settings_file(blocked + "/settings.ini", s);  // its folder is a file
  EXPECT_EQ(written.rfind(blocked + "/settings.ini: not saved (", 0), 0u) << written;
  if (geteuid() != 0) {  // root writes anywhere
    const std::string locked = dir + "/locked";
    std::filesystem::create_directories(locked);
    std::filesystem::permissions(locked, std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
    EXPECT_NE(fv::write_settings_file(locked + "/settings.ini", s), "");
    std::filesystem::permissions(locked, std::filesystem::perms::owner_all);
  }
}

// A FIFO would block a plain open until a writer came; a huge file is not the viewer's.
TEST(ViewerSettingsStore, AFifoOrAHugeFileIsRefusedWithoutWaiting) {
  const std::string dir = scratch("odd_kinds");
  const std::string fifo = dir + "/settings.ini";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  fv::StoredSettings s;
  EXPECT_EQ(fv::read_settings_file(fifo, s), fifo + ": is a FIFO (named pipe), not a regular file: ignored, using the defaults");
  const std::string huge = dir + "/huge.ini";
  write_text(huge, std::string(2 << 20, '#'));  // comment lines only: it would parse
  const std::string problem = fv::read_settings_file(huge, s);
  EXPECT_EQ(problem.rfind(huge + ": the file is ", 0), 0u) << problem;
  EXPECT_NE(problem.find("ignored, using the defaults"), std::string::npos) << problem;
}

TEST(ViewerSettingsStore, RecentFilesAreNewestFirstOnceAndCut) {
  std::vector<std::string> recent;
  for (int i = 0; i < 15; ++i) fv::add_recent_file(recent, "/s/" + std::to_string(i));
  fv::add_recent_file(recent, "/s/10");
  ASSERT_EQ(recent.size(), fv::kMaxRecentFiles);
  EXPECT_EQ(recent[0], "/s/10");
  EXPECT_EQ(recent[1], "/s/14");
  EXPECT_EQ(std::count(recent.begin(), recent.end(), "/s/10"), 1);
}

TEST(ViewerSettingsStore, TheConfigFolderFollowsXdg) {
  const char* old_xdg = std::getenv("XDG_CONFIG_HOME");
  const std::string saved = old_xdg ? old_xdg : "";
  setenv("XDG_CONFIG_HOME", "/tmp/xdg_here", 1);
  EXPECT_EQ(fv::config_dir(), "/tmp/xdg_here/flashgs");
  setenv("XDG_CONFIG_HOME", "relative/ignored", 1);
  EXPECT_EQ(fv::config_dir(), std::string(std::getenv("HOME")) + "/.config/flashgs");
  if (old_xdg) setenv("XDG_CONFIG_HOME", saved.c_str(), 1);
  else unsetenv("XDG_CONFIG_HOME");
}
