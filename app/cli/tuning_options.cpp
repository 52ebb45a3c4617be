// --set, --tuning and --list-tuning (see tuning_options.h).
#include "tuning_options.h"

#include <cstdio>

#include "flashgs/error.h"

namespace flashgs::cli {

namespace {

std::string knob_names() {
  std::string names;
  for (const TuningKnob& knob : kTuningKnobs) names += std::string(names.empty() ? "" : ", ") + knob.name;
  return names;
}

// "a,b,,c" -> {"a", "b", "", "c"}: empty items are kept, so that the knob's parse refuses them.
std::vector<std::string> split_values(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  for (std::size_t comma; (comma = text.find(',', start)) != std::string::npos; start = comma + 1)
    out.push_back(text.substr(start, comma - start));
  out.push_back(text.substr(start));
  return out;
}

}  // namespace

void TuningOptions::add_to(CLI::App* command) {
  command->add_option("--set", settings,
                      "NAME=VALUE: a backend tuning knob for every run (" + knob_names() +
                          "; see --list-tuning; the environment's FLASHGS_<NAME> is the default); may be repeated")
      ->allow_extra_args(false);  // one value each: a scene path after it stays the scene
  command->add_option("--tuning", sweeps,
                      "NAME=V1,V2,...: run every configuration once per value of the knob; may be repeated "
                      "(every combination)")
      ->allow_extra_args(false);
  command->add_flag_callback(
      "--list-tuning",
      [] {
        std::printf("Backend tuning knobs (speed, never the image; docs/TUNING.md):\n%s", tuning_listing().c_str());
        throw CLI::Success();
      },
      "list the backend tuning knobs, their values and defaults, and exit");
}

BackendTuning TuningOptions::base() const {
  BackendTuning tuning = tuning_from_environment();
  for (const std::string& setting : settings) apply_tuning_setting(tuning, setting, "--set");
  return tuning;
}

std::vector<TuningVariant> TuningOptions::variants() const {
  std::vector<TuningVariant> variants{{"", base()}};
  for (const std::string& sweep : sweeps) {
    const std::size_t equals = sweep.find('=');
    const TuningKnob* knob = find_tuning_knob(sweep.substr(0, equals));
    if (equals == std::string::npos || !knob)
      throw Error("--tuning \"" + sweep + "\": expected NAME=V1,V2,... with a NAME of --list-tuning");
    std::vector<TuningVariant> next;
    for (const TuningVariant& variant : variants)
      for (const std::string& value : split_values(sweep.substr(equals + 1))) {
        TuningVariant v = variant;
        apply_tuning_value(v.tuning, *knob, value, "--tuning");
        v.label += std::string(v.label.empty() ? "" : " ") + knob->name + "=" + value;
        next.push_back(v);
      }
    variants = std::move(next);
  }
  return variants;
}

std::string with_tuning_label(const std::string& name, const TuningVariant& variant) {
  return variant.label.empty() ? name : name + " " + variant.label;
}

}  // namespace flashgs::cli
