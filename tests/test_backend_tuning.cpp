// The tuning knobs' table (flashgs/backend_tuning.h): the environment each one reads, the strict
// parse of typed values, and docs/TUNING.md as generated from the table.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "flashgs/backend_tuning.h"
#include "flashgs/error.h"

namespace flashgs {
namespace {

// Sets a variable for the life of the object, and removes it after.
class ScopedVariable {
 public:
  ScopedVariable(const std::string& name, const char* value) : name_(name) { setenv(name.c_str(), value, 1); }
  ~ScopedVariable() { unsetenv(name_.c_str()); }

 private:
  std::string name_;
};

std::string error_of(BackendTuning& tuning, const std::string& setting) {
  try {
    apply_tuning_setting(tuning, setting, "--set");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(BackendTuning, EveryKnobHasOneMemberAndAUniqueName) {
  std::set<std::string> names;
  for (const TuningKnob& knob : kTuningKnobs) {
    EXPECT_TRUE(names.insert(knob.name).second) << knob.name;
    EXPECT_EQ(knob.kind == TuningKind::text, knob.text != nullptr) << knob.name;
    EXPECT_EQ(knob.kind == TuningKind::text, knob.number == nullptr) << knob.name;
    EXPECT_EQ(find_tuning_knob(knob.name), &knob);
  }
  EXPECT_EQ(find_tuning_knob("no_such_knob"), nullptr);
  EXPECT_EQ(tuning_variable(*find_tuning_knob("bin_sort")), "FLASHGS_BIN_SORT");
}

// The defaults are the struct's initialisers; the table's words say the same.
TEST(BackendTuning, DefaultsAgreeWithTheTablesWords) {
  const BackendTuning defaults;
  for (const TuningKnob& knob : kTuningKnobs) {
    const std::string value = tuning_value_text(defaults, knob);
    std::string words = knob.default_text;
    words.erase(std::remove(words.begin(), words.end(), ','), words.end());
    if (knob.kind == TuningKind::text) {
      EXPECT_EQ(value, "") << knob.name;
      continue;
    }
    EXPECT_EQ(words.rfind(value, 0), 0u) << knob.name << ": default " << value << ", described as " << knob.default_text;
    if (knob.kind != TuningKind::mode) {
      const long long number = defaults.*knob.number;
      EXPECT_TRUE(number >= knob.min && number <= knob.max) << knob.name;
    }
  }
}

TEST(BackendTuning, TheEnvironmentSetsEachKnobAsTheBackendsReadIt) {
  EXPECT_EQ(tuning_summary(tuning_from_environment()), tuning_summary(BackendTuning{}))
      << "a FLASHGS_ tuning variable is set in the test's environment";
  {
    ScopedVariable a("FLASHGS_BIN_SORT", "0"), b("FLASHGS_CHUNK_CULL", "1"), c("FLASHGS_SORT_KEY_BITS", "8"),
        d("FLASHGS_LARGE_BOX_TILES", "99999999"), e("FLASHGS_BLEND_REGION_WIDTH", "12"),
        f("FLASHGS_INITIAL_RECORDS", "1"), g("FLASHGS_CPU_SIMD", "AVX2"), h("FLASHGS_SPATIAL_ORDER", "yes");
    const BackendTuning t = tuning_from_environment();
    EXPECT_EQ(t.bin_sort, 0);
    EXPECT_EQ(t.chunk_cull, 1);
    EXPECT_EQ(t.sort_key_bits, 16);         // clamped into 16-32
    EXPECT_EQ(t.large_box_tiles, 1 << 20);  // clamped
    EXPECT_EQ(t.blend_region_width, 8);     // not 16: the default
    EXPECT_EQ(t.initial_records, 1);
    EXPECT_EQ(t.cpu_simd, "AVX2");
    EXPECT_EQ(t.spatial_order, 0);          // not a number: read as 0
    EXPECT_EQ(t.emit_bin_counts, kTuningAuto);  // unset
    EXPECT_EQ(tuning_changes(t),
              "bin_sort=0 sort_key_bits=16 chunk_cull=1 spatial_order=0 large_box_tiles=1048576 initial_records=1 "
              "cpu_simd=AVX2");
  }
  const ScopedVariable region("FLASHGS_BLEND_REGION_WIDTH", "16");
  EXPECT_EQ(tuning_from_environment().blend_region_width, 16);
}

TEST(BackendTuning, TypedValuesAreCheckedAgainstTheKnobsRange) {
  BackendTuning t;
  EXPECT_EQ(error_of(t, "bin_sort=0"), "");
  EXPECT_EQ(t.bin_sort, 0);
  EXPECT_EQ(error_of(t, "bin_sort=auto"), "");
  EXPECT_EQ(t.bin_sort, kTuningAuto);
  EXPECT_EQ(error_of(t, "sort_key_bits=24"), "");
  EXPECT_EQ(t.sort_key_bits, 24);
  EXPECT_EQ(error_of(t, "blend_region_width=16"), "");
  EXPECT_EQ(t.blend_region_width, 16);
  EXPECT_EQ(error_of(t, "cpu_simd=SSE4"), "");
  EXPECT_EQ(t.cpu_simd, "SSE4");
  const BackendTuning before = t;
  EXPECT_EQ(error_of(t, "sort_key_bits=33"), "--set: sort_key_bits=\"33\": expected 16-32");
  EXPECT_EQ(error_of(t, "bin_sort=2"), "--set: bin_sort=\"2\": expected auto, 0 or 1");
  EXPECT_EQ(error_of(t, "blend_stop_bound=auto"), "--set: blend_stop_bound=\"auto\": expected 0 or 1");
  EXPECT_EQ(error_of(t, "blend_region_width=12"), "--set: blend_region_width=\"12\": expected 8 or 16");
  EXPECT_EQ(error_of(t, "large_box_tiles=3x"), "--set: large_box_tiles=\"3x\": expected 1-1048576");
  EXPECT_EQ(error_of(t, "large_box_tiles="), "--set: large_box_tiles=\"\": expected 1-1048576");
  EXPECT_EQ(error_of(t, "initial_records=99999999999999999999"),
            "--set: initial_records=\"99999999999999999999\": expected 1-1099511627776");
  EXPECT_EQ(error_of(t, "no_such_knob=1"), "--set \"no_such_knob=1\": expected NAME=VALUE with a NAME of --list-tuning");
  EXPECT_EQ(error_of(t, "bin_sort"), "--set \"bin_sort\": expected NAME=VALUE with a NAME of --list-tuning");
  EXPECT_EQ(tuning_summary(t), tuning_summary(before)) << "a refused value changed the tuning";
}

TEST(BackendTuning, ListingAndSummaryNameEveryKnob) {
  const std::string listing = tuning_listing(), summary = tuning_summary(BackendTuning{});
  for (const TuningKnob& knob : kTuningKnobs) {
    EXPECT_NE(listing.find(std::string(knob.name) + " ("), std::string::npos) << knob.name;
    EXPECT_NE(listing.find(tuning_variable(knob)), std::string::npos) << knob.name;
    EXPECT_NE(summary.find(std::string(knob.name) + "="), std::string::npos) << knob.name;
  }
  EXPECT_EQ(tuning_changes(BackendTuning{}), "");
}

// docs/TUNING.md holds the table exactly as the code generates it: a knob added, removed or
// described anew in kTuningKnobs fails here, printing the table to paste into the docs.
TEST(BackendTuning, TheDocsTableIsTheGeneratedOne) {
  std::ifstream in(std::string(FLASHGS_PROJECT_SOURCE_DIR) + "/docs/TUNING.md");
  ASSERT_TRUE(in) << "docs/TUNING.md is missing";
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find(tuning_table_markdown()), std::string::npos)
      << "docs/TUNING.md's table differs from kTuningKnobs; the generated table:\n"
      << tuning_table_markdown();
}

}  // namespace
}  // namespace flashgs
