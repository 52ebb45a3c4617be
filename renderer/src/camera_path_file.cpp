// Camera path files: our keyframe JSON read with validation and written back, and nerfstudio's camera_path.json read.
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/file_write.h"
#include "flashgs/keyframe_path.h"

namespace flashgs {
namespace {

using nlohmann::json;

constexpr const char kFormat[] = "flashgs camera path";
constexpr int kVersion = 1;
// A path of a few thousand keys is a few MB.
constexpr std::size_t kMaxPathFileBytes = 64000000;

// A finite number at `field` of `entry`, within [lo, hi]; else an error naming `where`.
double number_at(const json& entry, const char* field, double lo, double hi, const std::string& where) {
  if (!entry.contains(field)) throw Error(where + ": missing field \"" + field + "\"");
  const json& v = entry.at(field);
  if (!v.is_number()) throw Error(where + ": \"" + field + "\" is not a finite number");
  const double d = v.get<double>();
  if (!(d >= lo && d <= hi)) {
    char range[96];
    std::snprintf(range, sizeof range, " is %g, outside %g..%g", d, lo, hi);
    throw Error(where + ": \"" + field + "\"" + range);
  }
  return d;
}

// `count` finite numbers from the array at `field` (nested arrays flattened row by row).
std::vector<double> numbers_at(const json& entry, const char* field, std::size_t count, const std::string& where) {
  if (!entry.contains(field)) throw Error(where + ": missing field \"" + field + "\"");
  std::vector<double> out;
  const auto add = [&](const json& v) {
    if (!v.is_number()) throw Error(where + ": \"" + field + "\" holds something that is not a finite number");
    const double d = v.get<double>();
    if (!std::isfinite(d) || std::abs(d) > 1e30) throw Error(where + ": \"" + field + "\" holds a non-finite value");
    out.push_back(d);
  };
  const json& a = entry.at(field);
  if (!a.is_array()) throw Error(where + ": \"" + field + "\" is not an array");
  for (const json& v : a) {
    if (v.is_array())
      for (const json& w : v) add(w);
    else
      add(v);
  }
  if (out.size() != count)
    throw Error(where + ": \"" + field + "\" has " + std::to_string(out.size()) + " numbers, not " + std::to_string(count));
  return out;
}

// A rotation's columns must be unit length and orthogonal (to a typed file's precision).
void check_rotation(const float* m, const std::string& where) {
  for (int a = 0; a < 3; ++a)
    for (int b = a; b < 3; ++b) {
      const double dot = double(m[a]) * m[b] + double(m[3 + a]) * m[3 + b] + double(m[6 + a]) * m[6 + b];
      if (std::abs(dot - (a == b ? 1.0 : 0.0)) > 1e-3)
        throw Error(where + ": \"rotation\" is not a rotation (its columns are not orthonormal)");
    }
  const double det = double(m[0]) * (double(m[4]) * m[8] - double(m[5]) * m[7]) -
                     double(m[1]) * (double(m[3]) * m[8] - double(m[5]) * m[6]) +
                     double(m[2]) * (double(m[3]) * m[7] - double(m[4]) * m[6]);
  if (det < 0) throw Error(where + ": \"rotation\" is a reflection, not a rotation");
}

void read_size(const json& doc, KeyframePath& p, const std::string& name) {
  p.fps = static_cast<int>(std::lround(number_at(doc, "fps", 1, kMaxPathFps, name)));
  if (doc.contains("resolution")) {
    const std::vector<double> r = numbers_at(doc, "resolution", 2, name);
    for (double v : r)
      if (!(v >= 1 && v <= kMaxPathSide) || v != std::floor(v))
        throw Error(name + ": \"resolution\" must be two whole numbers 1.." + std::to_string(kMaxPathSide));
    p.width = int(r[0]);
    p.height = int(r[1]);
  }
}

KeyframePath parse_ours(const json& doc, const std::string& name) {
  KeyframePath p;
  if (number_at(doc, "version", 1, 1e9, name) > kVersion)
    throw Error(name + ": camera path version " + doc.at("version").dump() + " is newer than this program reads (" +
                std::to_string(kVersion) + ")");
  read_size(doc, p, name);
  if (doc.contains("easing")) {
    const json& e = doc.at("easing");
    if (e == "linear") p.easing = PathEasing::linear;
    else if (e == "ease_in_out") p.easing = PathEasing::ease_in_out;
    else throw Error(name + ": \"easing\" must be \"linear\" or \"ease_in_out\"");
  }
  if (!doc.contains("keyframes") || !doc.at("keyframes").is_array())
    throw Error(name + ": missing array \"keyframes\"");
  const json& keys = doc.at("keyframes");
  if (keys.empty()) throw Error(name + ": \"keyframes\" is empty");
  if (keys.size() > kMaxKeyframes) throw Error(name + ": more than " + std::to_string(kMaxKeyframes) + " keyframes");
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const std::string where = name + " keyframe " + std::to_string(i);
    if (!keys[i].is_object()) throw Error(where + ": not an object");
    Keyframe k;
    k.time_s = number_at(keys[i], "time", 0, 1e6, where);
    if (!p.keys.empty() && k.time_s < p.keys.back().time_s)
      throw Error(where + ": its time comes before keyframe " + std::to_string(i - 1) + "'s (keys are in time order)");
    const std::vector<double> pos = numbers_at(keys[i], "position", 3, where);
    const std::vector<double> rot = numbers_at(keys[i], "rotation", 9, where);
    for (int c = 0; c < 3; ++c) k.position[c] = float(pos[c]);
    for (int c = 0; c < 9; ++c) k.camera_to_world[c] = float(rot[c]);
    check_rotation(k.camera_to_world, where);
    k.fov_x_degrees = float(number_at(keys[i], "fov_x_degrees", 1, 179, where));
    p.keys.push_back(k);
  }
  return p;
}

// nerfstudio: "camera_path" holds one entry per frame, "camera_to_world" a row-major 4x4 in
// OpenGL axes (y up, z backwards) and "fov" the vertical field of view in degrees.
KeyframePath parse_nerfstudio(const json& doc, const std::string& name) {
  KeyframePath p;
  read_size(doc, p, name);
  if (doc.contains("render_width") && doc.contains("render_height")) {
    p.width = int(number_at(doc, "render_width", 1, kMaxPathSide, name));
    p.height = int(number_at(doc, "render_height", 1, kMaxPathSide, name));
  }
  p.easing = PathEasing::linear;  // its frames are already eased
  const json& frames = doc.at("camera_path");
  if (!frames.is_array() || frames.empty()) throw Error(name + ": \"camera_path\" is not a list of frames");
  if (frames.size() > kMaxKeyframes) throw Error(name + ": more than " + std::to_string(kMaxKeyframes) + " frames");
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::string where = name + " camera_path frame " + std::to_string(i);
    if (!frames[i].is_object()) throw Error(where + ": not an object");
    const std::vector<double> m = numbers_at(frames[i], "camera_to_world", 16, where);
    const double fov_y = number_at(frames[i], "fov", 1, 179, where);
    const double aspect =
        frames[i].contains("aspect") ? number_at(frames[i], "aspect", 1e-3, 1e3, where) : double(p.width) / p.height;
    Keyframe k;
    k.time_s = double(i) / p.fps;
    for (int r = 0; r < 3; ++r) {
      k.position[r] = float(m[r * 4 + 3]);
      // OpenGL's y up and z backwards are OpenCV's -y and -z: the second and third columns negated.
      k.camera_to_world[r * 3 + 0] = float(m[r * 4 + 0]);
      k.camera_to_world[r * 3 + 1] = float(-m[r * 4 + 1]);
      k.camera_to_world[r * 3 + 2] = float(-m[r * 4 + 2]);
    }
    check_rotation(k.camera_to_world, where);
    k.fov_x_degrees = float(2.0 * std::atan(std::tan(0.5 * fov_y * M_PI / 180.0) * aspect) * 180.0 / M_PI);
    p.keys.push_back(k);
  }
  return p;
}

}  // namespace

KeyframePath parse_camera_path(const std::string& json_text, const std::string& name) {
  json doc;
  try {
    doc = json::parse(json_text);
  } catch (const json::exception& e) {
    throw Error(name + ": not valid JSON (" + printable_message(e.what()) + ")");
  }
  if (!doc.is_object()) throw Error(name + ": not a camera path (the JSON is not an object)");
  if (doc.contains("format") && doc.at("format") == kFormat) return parse_ours(doc, name);
  if (doc.contains("camera_path")) return parse_nerfstudio(doc, name);
  throw Error(name + ": not a camera path (neither \"format\": \"" + kFormat + "\" nor nerfstudio's \"camera_path\")");
}

KeyframePath read_camera_path(const std::string& path) {
  const std::vector<char> bytes = read_regular_file(path, kMaxPathFileBytes);
  return parse_camera_path(std::string(bytes.begin(), bytes.end()), path);
}

void write_camera_path(const KeyframePath& p, const std::string& path) {
  json keys = json::array();
  for (const Keyframe& k : p.keys) {
    json rotation = json::array();
    for (int r = 0; r < 3; ++r)
      rotation.push_back({k.camera_to_world[r * 3], k.camera_to_world[r * 3 + 1], k.camera_to_world[r * 3 + 2]});
    keys.push_back({{"time", k.time_s},
                    {"position", {k.position[0], k.position[1], k.position[2]}},
                    {"rotation", rotation},
                    {"fov_x_degrees", k.fov_x_degrees}});
  }
  const json doc = {{"format", kFormat},          {"version", kVersion},
                    {"fps", p.fps},               {"resolution", {p.width, p.height}},
                    {"easing", easing_name(p.easing)}, {"keyframes", keys}};
  write_file_atomically(path, doc.dump(1) + "\n");
}

}  // namespace flashgs
