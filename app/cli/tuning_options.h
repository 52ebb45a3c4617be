// The backend tuning knobs on a subcommand's command line: --set, a --tuning sweep and
// --list-tuning (the knobs themselves: flashgs/backend_tuning.h).
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "flashgs/backend_tuning.h"

namespace flashgs::cli {

// One tuning a sweep runs: `label` names the swept values ("bin_sort=0 sort_key_bits=24"; empty
// without --tuning).
struct TuningVariant {
  std::string label;
  BackendTuning tuning;
};

struct TuningOptions {
  std::vector<std::string> settings;  // --set NAME=VALUE
  std::vector<std::string> sweeps;    // --tuning NAME=V1,V2,...
  bool list = false;                  // --list-tuning

  void add_to(CLI::App* command);
  // The environment's tuning with every --set applied. Throws flashgs::Error naming the option
  // and the knob.
  BackendTuning base() const;
  // base(), once per combination of the --tuning values, in the order typed (throws as base).
  std::vector<TuningVariant> variants() const;
};

// `name` with the variant's label after it, as a table row is named.
std::string with_tuning_label(const std::string& name, const TuningVariant& variant);

}  // namespace flashgs::cli
