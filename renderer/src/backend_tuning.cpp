// The tuning knobs' environment, parsing and listings (see flashgs/backend_tuning.h).
#include "flashgs/backend_tuning.h"

#include <cctype>
#include <cerrno>
#include <cstdlib>

#include "flashgs/error.h"

namespace flashgs {

namespace {

// A knob's value from its variable's text, read as the backends always read it (atoi-like:
// leading digits, anything else 0), then brought into the knob's range.
long long value_from_environment(const TuningKnob& knob, const char* text, long long current) {
  const long long typed = std::atoll(text);
  switch (knob.kind) {
    case TuningKind::mode:
    case TuningKind::flag: return typed != 0 ? 1 : 0;
    case TuningKind::choice: return typed == knob.max ? knob.max : knob.min;
    case TuningKind::number: return typed < knob.min ? knob.min : (typed > knob.max ? knob.max : typed);
    case TuningKind::text: break;
  }
  return current;
}

// The knob's values in words: "auto, 0 or 1", "16-32", "8 or 16", "a SIMD target name".
std::string values_text(const TuningKnob& knob) {
  switch (knob.kind) {
    case TuningKind::mode: return "auto, 0 or 1";
    case TuningKind::flag: return "0 or 1";
    case TuningKind::choice: return std::to_string(knob.min) + " or " + std::to_string(knob.max);
    case TuningKind::number: return std::to_string(knob.min) + "-" + std::to_string(knob.max);
    case TuningKind::text: return "a SIMD target name";
  }
  return "";
}

// Digits with an optional leading minus, nothing else, within a long long.
bool parse_integer(const std::string& text, long long& value) {
  if (text.empty()) return false;
  for (std::size_t i = 0; i < text.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(text[i])) && !(i == 0 && text[i] == '-' && text.size() > 1)) return false;
  errno = 0;
  value = std::strtoll(text.c_str(), nullptr, 10);
  return errno == 0;
}

}  // namespace

std::string tuning_variable(const TuningKnob& knob) {
  std::string name = "FLASHGS_";
  for (const char* c = knob.name; *c; ++c) name += static_cast<char>(std::toupper(static_cast<unsigned char>(*c)));
  return name;
}

const TuningKnob* find_tuning_knob(const std::string& name) {
  for (const TuningKnob& knob : kTuningKnobs)
    if (name == knob.name) return &knob;
  return nullptr;
}

BackendTuning tuning_from_environment() {
  BackendTuning tuning;
  for (const TuningKnob& knob : kTuningKnobs) {
    const char* text = std::getenv(tuning_variable(knob).c_str());
    if (!text) continue;
    if (knob.kind == TuningKind::text) tuning.*knob.text = text;
    else tuning.*knob.number = value_from_environment(knob, text, tuning.*knob.number);
  }
  return tuning;
}

void apply_tuning_value(BackendTuning& tuning, const TuningKnob& knob, const std::string& value, const std::string& what) {
  if (knob.kind == TuningKind::text) {
    tuning.*knob.text = value;
    return;
  }
  long long number = 0;
  const bool automatic = knob.kind == TuningKind::mode && value == "auto";
  const bool valid = automatic || (parse_integer(value, number) &&
                                   (knob.kind == TuningKind::choice ? number == knob.min || number == knob.max
                                                                    : number >= knob.min && number <= knob.max));
  if (!valid)
    throw Error(what + ": " + knob.name + "=\"" + value + "\": expected " + values_text(knob));
  tuning.*knob.number = automatic ? kTuningAuto : number;
}

void apply_tuning_setting(BackendTuning& tuning, const std::string& setting, const std::string& what) {
  const std::size_t equals = setting.find('=');
  const TuningKnob* knob = find_tuning_knob(setting.substr(0, equals));
  if (equals == std::string::npos || !knob)
    throw Error(what + " \"" + setting + "\": expected NAME=VALUE with a NAME of --list-tuning");
  apply_tuning_value(tuning, *knob, setting.substr(equals + 1), what);
}

std::string tuning_value_text(const BackendTuning& tuning, const TuningKnob& knob) {
  if (knob.kind == TuningKind::text) return tuning.*knob.text;
  const long long value = tuning.*knob.number;
  return knob.kind == TuningKind::mode && value == kTuningAuto ? "auto" : std::to_string(value);
}

std::string tuning_summary(const BackendTuning& tuning) {
  std::string out;
  for (const TuningKnob& knob : kTuningKnobs)
    out += std::string(out.empty() ? "" : " ") + knob.name + "=" + tuning_value_text(tuning, knob);
  return out;
}

std::string tuning_changes(const BackendTuning& tuning) {
  const BackendTuning defaults;
  std::string out;
  for (const TuningKnob& knob : kTuningKnobs) {
    const std::string value = tuning_value_text(tuning, knob);
    if (value != tuning_value_text(defaults, knob))
      out += std::string(out.empty() ? "" : " ") + knob.name + "=" + value;
  }
  return out;
}

std::string tuning_listing() {
  std::string out;
  for (const TuningKnob& knob : kTuningKnobs) {
    out += std::string(knob.name) + " (" + knob.backend + "; " + values_text(knob) + "; " + tuning_variable(knob) +
           ")\n    default: " + knob.default_text + "\n    " + knob.trades + "\n";
  }
  return out;
}

std::string tuning_table_markdown() {
  std::string out =
      "| name | variable | values | default | what it trades | where it was measured |\n"
      "|---|---|---|---|---|---|\n";
  for (const TuningKnob& knob : kTuningKnobs)
    out += std::string("| `") + knob.name + "` | `" + tuning_variable(knob) + "` | " + values_text(knob) + " | " +
           knob.default_text + " | " + knob.trades + " | " + knob.measured + " |\n";
  return out;
}

}  // namespace flashgs
