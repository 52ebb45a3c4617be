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

// Every environment variable the code reads to tune a frame is a row of docs/TUNING.md: a knob
// added without its row (default, what it trades, where it was measured) fails here.
TEST(Repository, EveryTuningVariableIsDocumented) {
  const fs::path root(FLASHGS_PROJECT_SOURCE_DIR);
  const std::string table = read_all(root / "docs" / "TUNING.md");
  ASSERT_FALSE(table.empty()) << "docs/TUNING.md is missing";
  const std::regex read_variable(std::string("getenv\\(\"(FLASHGS_") + "[A-Z0-9_]+)\"\\)");
  std::vector<std::string> found, missing;
  for (const char* part : {"cuda", "renderer", "app"})
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(root / part)) {
      if (!entry.is_regular_file()) continue;
      const std::string text = read_all(entry.path());
      for (std::sregex_iterator it(text.begin(), text.end(), read_variable), end; it != end; ++it) {
        const std::string name = (*it)[1].str();
        found.push_back(name);
        if (table.find("| `" + name + "` |") == std::string::npos) missing.push_back(name + " (" + entry.path().string() + ")");
      }
    }
  EXPECT_GE(found.size(), 10u) << "the scan found too few variables: the pattern no longer matches the code";
  std::string report;
  for (const std::string& m : missing) report += m + "\n";
  EXPECT_TRUE(missing.empty()) << "variables read but not in docs/TUNING.md:\n" << report;
}
