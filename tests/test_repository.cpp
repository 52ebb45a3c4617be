// The repository speaks of the product: no document, comment or file name labels its text by
// the development round it came from ("session N", a raw log named h200_sNN_...). Figures name
// their hardware, date and commit instead. This walks the source tree and names each offending
// file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

// The patterns are built from pieces so that this file does not match them itself.
const std::vector<std::regex>& round_patterns() {
  static const std::vector<std::regex> patterns = {
      std::regex(std::string("[Ss]ess") + "ions? [0-9]+"),            // a round by number
      std::regex(std::string("_s") + "[0-9]{2}_"),                    // a raw log named by round
      std::regex(std::string("PERFORMANCE\\.md,? ") + "v[0-9]+\\b"),  // a log entry by round
      std::regex(std::string("device ") + "tool"),                    // the tool, not the product
  };
  return patterns;
}

bool is_text(const std::string& bytes) { return bytes.find('\0') == std::string::npos; }

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// Every offence in one file or folder, as "path:line: text".
void scan(const fs::path& root, const fs::path& path, std::vector<std::string>& offences) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(path, ec)) {
      const std::string name = entry.path().filename().string();
      if (name == ".git" || name.rfind("build", 0) == 0) continue;
      if (entry.is_symlink(ec)) continue;
      scan(root, entry.path(), offences);
    }
    return;
  }
  if (!fs::is_regular_file(path, ec)) return;
  const std::string relative = fs::relative(path, root, ec).string();
  for (const std::regex& pattern : round_patterns())
    if (std::regex_search(relative, pattern)) offences.push_back(relative + ": the file's name");
  const std::string bytes = read_all(path);
  if (!is_text(bytes)) return;
  std::istringstream lines(bytes);
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number)
    for (const std::regex& pattern : round_patterns())
      if (std::regex_search(line, pattern)) {
        offences.push_back(relative + ":" + std::to_string(number) + ": " + line);
        break;
      }
}

}  // namespace

TEST(Repository, PatternsCatchRoundLabels) {
  const std::vector<std::string> labelled = {std::string("in sess") + "ion 18's build",
                                             std::string("Sess") + "ions 32-34 measured",
                                             std::string("docs/bench/h200_s") + "24_drafts.txt",
                                             std::string("docs/PERFORMANCE.md ") + "v35"};
  for (const std::string& text : labelled) {
    bool caught = false;
    for (const std::regex& pattern : round_patterns()) caught = caught || std::regex_search(text, pattern);
    EXPECT_TRUE(caught) << text;
  }
  const std::vector<std::string> product = {"SOG v2 (PlayCanvas)", "SPZ version 3", "gsplat v1.6.0",
                                            "another X session's input",
                                            "docs/bench/h200_2026-12-04_drafts.txt", "v3dg_donut"};
  for (const std::string& text : product)
    for (const std::regex& pattern : round_patterns()) EXPECT_FALSE(std::regex_search(text, pattern)) << text;
}

TEST(Repository, NoRoundLabelsInTheSourceTree) {
  const fs::path root(FLASHGS_PROJECT_SOURCE_DIR);
  ASSERT_TRUE(fs::exists(root / "README.md")) << root;
  std::vector<std::string> offences;
  for (const char* part : {"README.md", "docs", "app", "renderer", "cuda", "tests", "tools"})
    scan(root, root / part, offences);
  std::string report;
  for (const std::string& offence : offences) report += offence + "\n";
  EXPECT_TRUE(offences.empty()) << offences.size() << " lines label text by development round:\n"
                                << report;
}

// The environment tunes a frame in one place: tuning_from_environment reads every knob of the
// documented table (flashgs/backend_tuning.h, docs/TUNING.md). A renderer reading a variable of
// its own, or the app reading a FLASHGS_ one, would be a knob outside the table.
TEST(Repository, OnlyTheTuningTableReadsTheEnvironment) {
  const fs::path root(FLASHGS_PROJECT_SOURCE_DIR);
  const fs::path reader = root / "renderer" / "src" / "backend_tuning.cpp";
  const std::regex any_read("getenv\\(");
  const std::regex flashgs_read(std::string("getenv\\(\"") + "FLASHGS_");
  std::vector<std::string> offences;
  std::size_t reads_in_reader = 0;
  for (const char* part : {"cuda", "renderer", "app"})
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(root / part)) {
      if (!entry.is_regular_file()) continue;
      const std::string text = read_all(entry.path());
      const bool renderer_side = std::string(part) != "app";
      const std::regex& pattern = renderer_side ? any_read : flashgs_read;
      const auto reads = static_cast<std::size_t>(
          std::distance(std::sregex_iterator(text.begin(), text.end(), pattern), std::sregex_iterator()));
      if (entry.path() == reader) reads_in_reader = reads;
      else if (reads > 0) offences.push_back(entry.path().string());
    }
  EXPECT_EQ(reads_in_reader, 1u) << reader << ": the one reader of the environment no longer matches the scan";
  std::string report;
  for (const std::string& offence : offences) report += offence + "\n";
  EXPECT_TRUE(offences.empty()) << "files reading the environment outside tuning_from_environment:\n" << report;
}
