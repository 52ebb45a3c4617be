// The switch table of options.h and what is derived from it: labels, the baseline, equality,
// the backends' view, the CLI's --no- flags and the report's sweep.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <iterator>
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/options.h"
#include "flashgs/splat_kernel.h"
#include "report_sweep.h"
#include "switch_flags.h"

namespace flashgs {

// What a failed EXPECT_EQ on two option sets prints.
void PrintTo(const RenderOptions& o, std::ostream* out) {
  *out << o.label() << " (tau " << o.tau << ", SH cap " << o.sh_degree_cap << (o.fp16_sh ? ", fp16 SH" : "") << ")";
}

namespace {

bool only_chars(const std::string& text, const char* allowed) {
  return !text.empty() && text.find_first_not_of(allowed) == std::string::npos;
}

// Every switch of the table at its default except `off`.
RenderOptions flash_without(const RenderSwitch& off) {
  RenderOptions o;
  o.*(off.member) = false;
  return o;
}

TEST(OptionsTable, NamesAndMembersAreUniqueAndWellFormed) {
  std::set<std::string> cli_names, labels, ui_names;
  std::vector<SwitchMember> members;
  for (const RenderSwitch& s : kRenderSwitches) {
    EXPECT_TRUE(cli_names.insert(s.cli_name).second) << "CLI name used twice: " << s.cli_name;
    EXPECT_TRUE(labels.insert(s.label).second) << "label used twice: " << s.label;
    EXPECT_TRUE(ui_names.insert(s.ui_name).second) << "checkbox name used twice: " << s.ui_name;
    EXPECT_TRUE(std::find(members.begin(), members.end(), s.member) == members.end())
        << s.label << ": its member is already another row's";
    members.push_back(s.member);
    // Flags are kebab-case; label tokens go into labels, file names and CSV headers.
    EXPECT_TRUE(only_chars(s.cli_name, "abcdefghijklmnopqrstuvwxyz0123456789-")) << s.cli_name;
    EXPECT_TRUE(only_chars(s.label, "abcdefghijklmnopqrstuvwxyz0123456789_")) << s.label;
    EXPECT_NE(s.backends, 0u) << s.label << ": no backend honours it";
    EXPECT_EQ(s.backends & ~kEveryBackend, 0u) << s.label << ": unknown backend bits";
    EXPECT_GT(std::strlen(s.help), 0u) << s.label;
    EXPECT_GT(std::strlen(s.paper), 0u) << s.label;
    for (Backend b : {Backend::cpu, Backend::cuda}) {
      if (s.honoured_by(b)) continue;
      EXPECT_GT(std::strlen(s.why_ignored), 0u) << s.label << ": greyed out without a reason";
    }
  }
}

TEST(OptionsTable, EachSwitchIsOnByDefaultAndTurnsOffItsLabelToken) {
  EXPECT_EQ(RenderOptions{}.label(), "flash");
  for (const RenderSwitch& s : kRenderSwitches) {
    EXPECT_TRUE(RenderOptions{}.*(s.member)) << s.label;
    const RenderOptions o = flash_without(s);
    EXPECT_EQ(o.label(), std::string("flash-no_") + s.label);
    EXPECT_NE(o, RenderOptions{}) << s.label << ": equality misses it";
  }
}

TEST(OptionsTable, LabelListsTheSwitchesOffInTableOrder) {
  RenderOptions o;
  std::string expected = "flash";
  for (const RenderSwitch& s : kRenderSwitches) {
    o.*(s.member) = false;
    expected += std::string("-no_") + s.label;
  }
  EXPECT_EQ(o.label(), expected);
}

TEST(OptionsTable, BaselineTurnsEverySwitchOffAndNothingElse) {
  RenderOptions b = RenderOptions::baseline();
  EXPECT_EQ(b.label(), "baseline");
  for (const RenderSwitch& s : kRenderSwitches) {
    EXPECT_FALSE(b.*(s.member)) << s.label;
    b.*(s.member) = true;
  }
  b.algorithm = Algorithm::flash;
  EXPECT_EQ(b, RenderOptions{});
}

TEST(OptionsTable, EqualitySeesTheFieldsBesideTheSwitches) {
  const RenderOptions flash;
  RenderOptions o;
  o.tau = 1.0f / 64.0f;
  EXPECT_NE(o, flash);
  o = flash;
  o.background[2] = 1.0f;
  EXPECT_NE(o, flash);
  o = flash;
  o.sh_degree_cap = 1;
  EXPECT_NE(o, flash);
  o = flash;
  o.collect_tile_counts = true;
  EXPECT_NE(o, flash);
  o = flash;
  o.fp16_sh = true;
  EXPECT_NE(o, flash);
  o = flash;
  o.algorithm = Algorithm::baseline;
  EXPECT_NE(o, flash);
  EXPECT_EQ(RenderOptions{}, flash);
}

TEST(OptionsTable, ABackendSeesOnlyTheSwitchesItHonours) {
  for (const RenderSwitch& s : kRenderSwitches) {
    const RenderOptions o = flash_without(s);
    for (Backend b : {Backend::cpu, Backend::cuda}) {
      const RenderOptions expected = s.honoured_by(b) ? o : RenderOptions{};
      EXPECT_EQ(o.seen_by(b), expected) << s.label << " on " << backend_name(b);
    }
  }
  EXPECT_EQ(RenderOptions::baseline().seen_by(Backend::cpu), RenderOptions::baseline());
}

TEST(OptionsTable, SingleSwitchConfigsAreBaselineFlashAndEachSwitchOff) {
  const std::vector<RenderOptions> configs = single_switch_configs();
  ASSERT_EQ(configs.size(), 2 + std::size(kRenderSwitches));
  EXPECT_EQ(configs[0], RenderOptions::baseline());
  EXPECT_EQ(configs[1], RenderOptions{});
  for (std::size_t k = 0; k < std::size(kRenderSwitches); ++k)
    EXPECT_EQ(configs[2 + k], flash_without(kRenderSwitches[k])) << kRenderSwitches[k].label;
}

RenderOptions parse_flags(const std::string& command_line) {
  CLI::App app;
  SwitchFlags flags;
  flags.add_to(&app);
  app.parse(command_line, false);
  RenderOptions o;
  flags.apply(&o);
  return o;
}

TEST(SwitchFlags, EachFlagTurnsOffItsSwitchAlone) {
  EXPECT_EQ(parse_flags(""), RenderOptions{});
  for (const RenderSwitch& s : kRenderSwitches)
    EXPECT_EQ(parse_flags(std::string("--no-") + s.cli_name), flash_without(s)) << s.cli_name;
}

TEST(SwitchFlags, EveryFlagAtOnceGivesEverySwitchOff) {
  std::string line;
  RenderOptions expected;
  for (const RenderSwitch& s : kRenderSwitches) {
    line += std::string(" --no-") + s.cli_name;
    expected.*(s.member) = false;
  }
  EXPECT_EQ(parse_flags(line), expected);
}

TEST(SwitchFlags, HelpNamesEveryFlagAndUnknownOnesAreRejected) {
  CLI::App app;
  SwitchFlags flags;
  flags.add_to(&app);
  const std::string help = app.help();
  for (const RenderSwitch& s : kRenderSwitches)
    EXPECT_NE(help.find(std::string("--no-") + s.cli_name), std::string::npos) << s.cli_name;
  EXPECT_THROW(parse_flags("--no-such-switch"), CLI::ParseError);
}

TEST(ReportSweep, EverySwitchIsSweptAloneAndLeftOut) {
  const std::vector<cli::SweepConfig> configs = cli::sweep_configs(SplatKernel::classic());
  std::set<std::string> names;
  for (const cli::SweepConfig& c : configs) EXPECT_TRUE(names.insert(c.name).second) << "swept twice: " << c.name;
  auto find = [&](const std::string& name) -> const cli::SweepConfig* {
    for (const cli::SweepConfig& c : configs)
      if (c.name == name) return &c;
    return nullptr;
  };
  for (const RenderSwitch& s : kRenderSwitches) {
    const bool gpu_only = !s.honoured_by(Backend::cpu);
    const cli::SweepConfig* left_out = find(std::string("no-") + s.label);
    ASSERT_NE(left_out, nullptr) << s.label << " is never left out";
    EXPECT_EQ(left_out->options, flash_without(s));
    EXPECT_EQ(left_out->gpu_only, gpu_only) << s.label;
    const cli::SweepConfig* alone = find(std::string(gpu_only ? "gpu-only-" : "only-") + s.label);
    ASSERT_NE(alone, nullptr) << s.label << " is never swept alone";
    EXPECT_TRUE(alone->options.*(s.member)) << s.label;
    // Alone: every other switch of its group (same backends) off, the rest at the defaults.
    for (const RenderSwitch& other : kRenderSwitches) {
      if (&other == &s) continue;
      EXPECT_EQ(alone->options.*(other.member), other.backends != s.backends) << s.label << " / " << other.label;
    }
  }
}

// fp16_sh and fp16_shape are precision options, not switches: off by default and for the
// baseline, seen by both backends, named in the label, part of equality, and swept by the
// report in a group of their own.
TEST(OptionsTable, Fp16OptionsAreOffByDefaultAndNamedInTheLabel) {
  EXPECT_FALSE(RenderOptions{}.fp16_sh);
  EXPECT_FALSE(RenderOptions::baseline().fp16_sh);
  EXPECT_FALSE(RenderOptions{}.fp16_shape);
  EXPECT_FALSE(RenderOptions::baseline().fp16_shape);
  RenderOptions o;
  o.fp16_sh = true;
  EXPECT_EQ(o.label(), "flash-fp16_sh");
  for (Backend b : {Backend::cpu, Backend::cuda}) EXPECT_TRUE(o.seen_by(b).fp16_sh) << backend_name(b);
  RenderOptions shape;
  shape.fp16_shape = true;
  EXPECT_EQ(shape.label(), "flash-fp16_shape");
  EXPECT_FALSE(shape == RenderOptions{});
  for (Backend b : {Backend::cpu, Backend::cuda}) EXPECT_TRUE(shape.seen_by(b).fp16_shape) << backend_name(b);
  RenderOptions b = RenderOptions::baseline();
  b.fp16_sh = b.fp16_shape = true;
  EXPECT_EQ(b.label(), "baseline-fp16_sh-fp16_shape");
}

// fp16_blend is a precision option of the CUDA blend only: off by default, named in the label,
// part of equality, and what the CPU sees of it is off (it renders the exact image).
TEST(OptionsTable, Fp16BlendIsACudaPrecisionOption) {
  EXPECT_FALSE(RenderOptions{}.fp16_blend);
  EXPECT_FALSE(RenderOptions::baseline().fp16_blend);
  RenderOptions o;
  o.fp16_blend = true;
  EXPECT_EQ(o.label(), "flash-fp16_blend");
  EXPECT_FALSE(o == RenderOptions{});
  EXPECT_TRUE(o.seen_by(Backend::cuda).fp16_blend);
  EXPECT_TRUE(o.seen_by(Backend::cpu) == RenderOptions{});
  const std::vector<RenderOptions> configs = fp16_blend_configs();
  ASSERT_EQ(configs.size(), 2u);
  EXPECT_EQ(configs[0].label(), "flash-fp16_blend");
  EXPECT_EQ(configs[1].label(), "flash-fp16_sh-fp16_shape-fp16_blend");
}

// The report sweeps the half blend alone and with the fp16 storage, on the GPU only.
TEST(ReportSweep, Fp16BlendIsSweptOnTheGpu) {
  std::map<std::string, RenderOptions> swept;
  for (const cli::SweepConfig& c : cli::sweep_configs(SplatKernel::classic()))
    if (c.options.fp16_blend) {
      EXPECT_EQ(c.group, "precision");
      EXPECT_TRUE(c.gpu_only) << c.name;
      swept[c.name] = c.options;
    }
  ASSERT_EQ(swept.size(), 2u);
  EXPECT_EQ(swept["fp16-blend"], fp16_blend_configs()[0]);
  EXPECT_EQ(swept["fp16-all-blend"], fp16_blend_configs()[1]);
}

TEST(ReportSweep, Fp16OptionsAreSweptOnEveryBackend) {
  std::map<std::string, RenderOptions> swept;
  for (const cli::SweepConfig& c : cli::sweep_configs(SplatKernel::classic())) {
    if ((!c.options.fp16_sh && !c.options.fp16_shape) || c.options.fp16_blend) continue;
    EXPECT_EQ(c.group, "precision");
    EXPECT_FALSE(c.gpu_only);
    swept[c.name] = c.options;
  }
  RenderOptions sh, shape, all;
  sh.fp16_sh = true;
  shape.fp16_shape = true;
  all.fp16_sh = all.fp16_shape = true;
  EXPECT_EQ(swept.size(), 3u);
  EXPECT_EQ(swept["fp16-sh"], sh);
  EXPECT_EQ(swept["fp16-shape"], shape);
  EXPECT_EQ(swept["fp16-all"], all);
}


// The kernel: classic by default for both algorithms, named in the label when it is not,
// part of equality, parsed strictly from what users type.
TEST(SplatKernelOption, ParsedStrictlyAndNamedInTheLabel) {
  EXPECT_EQ(RenderOptions{}.kernel, SplatKernel::classic());
  EXPECT_EQ(RenderOptions::baseline().kernel, SplatKernel::classic());
  EXPECT_EQ(parse_splat_kernel("classic", "--kernel"), SplatKernel::classic());
  EXPECT_EQ(parse_splat_kernel("antialiased", "--kernel"), SplatKernel::antialiased(0.3f));
  EXPECT_EQ(parse_splat_kernel("antialiased=0.1", "--kernel"), SplatKernel::antialiased(0.1f));
  for (const char* bad : {"", "Classic", "antialiased=", "antialiased=0", "antialiased=-0.1", "antialiased=nan",
                          "antialiased=inf", "antialiased= 0.1", "antialiased=0.1x", "antialiased=17", "mip"}) {
    try {
      parse_splat_kernel(bad, "--kernel");
      ADD_FAILURE() << "accepted \"" << bad << "\"";
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--kernel \"", 0), 0u) << e.what();
    }
  }
  // spec() reads back as the same kernel.
  for (const SplatKernel& k : {SplatKernel::classic(), SplatKernel::antialiased(), SplatKernel::antialiased(0.1f),
                               SplatKernel::antialiased(1.25f)})
    EXPECT_EQ(parse_splat_kernel(k.spec(), "--kernel"), k) << k.spec();
  RenderOptions aa;
  aa.kernel = SplatKernel::antialiased(0.1f);
  EXPECT_EQ(aa.label(), "flash-antialiased_0.1");
  EXPECT_FALSE(aa == RenderOptions{});
  aa.kernel = SplatKernel::antialiased();
  EXPECT_EQ(aa.label(), "flash-antialiased");
  EXPECT_FALSE(aa == RenderOptions{});
  EXPECT_TRUE(aa.seen_by(Backend::cpu).kernel == aa.kernel);
}

// The report draws every configuration with the trained kernel, and each other kernel once.
TEST(ReportSweep, KernelGroupHoldsTheOtherKernels) {
  for (const SplatKernel& trained : {SplatKernel::classic(), SplatKernel::antialiased(0.1f)}) {
    std::vector<SplatKernel> others;
    for (const cli::SweepConfig& c : cli::sweep_configs(trained)) {
      if (c.group != "kernel") {
        EXPECT_EQ(c.options.kernel, trained) << c.name;
        continue;
      }
      EXPECT_NE(c.options.kernel, trained) << c.name;
      EXPECT_EQ(c.name, "kernel=" + c.options.kernel.spec());
      others.push_back(c.options.kernel);
    }
    EXPECT_EQ(others.size(), 2u) << trained.spec();
  }
}

}  // namespace
}  // namespace flashgs
