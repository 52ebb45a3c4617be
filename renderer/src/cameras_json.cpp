// cameras.json in the 3DGS training-output format: read with validation, and written back.
#include <cmath>
#include <cstdio>
#include <limits>

#include <nlohmann/json.hpp>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/file_write.h"
#include "flashgs/io.h"

namespace flashgs {
namespace {

using nlohmann::json;

// Real camera files hold a few hundred cameras in a few hundred KB.
constexpr std::size_t kMaxCameraFileBytes = 64000000;
// Longest img_name kept; longer names are cut (they are only shown).
constexpr std::size_t kMaxCameraNameBytes = 200;
// Focal lengths in pixels outside this range are not a camera (a zero or denormal one divides by zero).
constexpr double kMinFocal = 1e-3, kMaxFocal = 1e9;

// A float holds the value: a double of 1e300 is finite, its float is not.
bool fits_float(double v) { return std::abs(v) <= static_cast<double>(std::numeric_limits<float>::max()); }

std::string number_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

double number_field(const json& entry, const char* field, const std::string& where) {
  if (!entry.contains(field)) throw Error(where + ": missing field \"" + field + "\"");
  const json& v = entry.at(field);
  if (!v.is_number()) throw Error(where + ": field \"" + field + "\" is not a number");
  const double d = v.get<double>();
  if (!fits_float(d)) throw Error(where + ": field \"" + field + "\" is not a finite float (" + number_text(d) + ")");
  return d;
}

void read_vector(const json& entry, const char* field, int n, double* out, const std::string& where) {
  if (!entry.contains(field)) throw Error(where + ": missing field \"" + field + "\"");
  const json& v = entry.at(field);
  if (!v.is_array() || static_cast<int>(v.size()) != n)
    throw Error(where + ": field \"" + field + "\" must be an array of " + std::to_string(n) + " numbers");
  for (int i = 0; i < n; ++i) {
    // JSON has no NaN/Inf literals; nlohmann writes them as null, so null means non-finite.
    if (!v[i].is_number()) throw Error(where + ": \"" + field + "\"[" + std::to_string(i) + "] is not a finite number");
    out[i] = v[i].get<double>();
    if (!fits_float(out[i]))
      throw Error(where + ": \"" + field + "\"[" + std::to_string(i) + "] is not a finite float (" +
                  number_text(out[i]) + ")");
  }
}

}  // namespace

std::vector<Camera> parse_cameras(const std::string& json_text, const std::string& name) {
  if (json_text.find_first_not_of(" \t\r\n") == std::string::npos)
    throw Error(name + ": the file is empty (expected a JSON array of cameras)");
  json doc;
  try {
    doc = json::parse(json_text);
  } catch (const json::exception& e) {  // parse errors, and numbers beyond double range
    throw Error(name + ": not valid JSON (" + printable_file_text(e.what(), 200) + ")");
  }
  if (!doc.is_array()) throw Error(name + ": expected a JSON array of cameras");
  if (doc.empty()) throw Error(name + ": the camera list is empty");
  std::vector<Camera> cameras;
  for (std::size_t i = 0; i < doc.size(); ++i) {
    const json& entry = doc[i];
    const std::string where = name + ": camera " + std::to_string(i);
    if (!entry.is_object()) throw Error(where + " is not an object");
    const double width = number_field(entry, "width", where);
    const double height = number_field(entry, "height", where);
    if (width < 1 || height < 1 || width > 65536 || height > 65536 || width != std::floor(width) ||
        height != std::floor(height))
      throw Error(where + ": width and height must be whole numbers in 1..65536");
    const double fx = number_field(entry, "fx", where);
    const double fy = number_field(entry, "fy", where);
    if (!(fx > 0) || !(fy > 0)) throw Error(where + ": fx and fy must be positive");
    if (fx < kMinFocal || fy < kMinFocal || fx > kMaxFocal || fy > kMaxFocal)
      throw Error(where + ": fx and fy must be between " + number_text(kMinFocal) + " and " + number_text(kMaxFocal) +
                  " pixels (fx = " + number_text(fx) + ", fy = " + number_text(fy) + ")");
    double position[3];
    read_vector(entry, "position", 3, position, where);
    if (!entry.contains("rotation") || !entry.at("rotation").is_array() || entry.at("rotation").size() != 3)
      throw Error(where + ": field \"rotation\" must be a 3x3 array");
    double rows[9];
    for (int r = 0; r < 3; ++r) {
      const json& row = entry.at("rotation")[r];
      if (!row.is_array() || row.size() != 3) throw Error(where + ": field \"rotation\" must be a 3x3 array");
      for (int c = 0; c < 3; ++c) {
        if (!row[c].is_number()) throw Error(where + ": rotation has a non-finite entry");
        rows[r * 3 + c] = row[c].get<double>();
        if (!std::isfinite(rows[r * 3 + c])) throw Error(where + ": rotation has a non-finite entry");
      }
    }
    check_rotation(rows, where);
    float r[9], c[3];
    for (int k = 0; k < 9; ++k) r[k] = static_cast<float>(rows[k]);
    for (int k = 0; k < 3; ++k) c[k] = static_cast<float>(position[k]);
    Camera camera = Camera::from_pose(static_cast<int>(width), static_cast<int>(height),
                                      static_cast<float>(fx), static_cast<float>(fy), r, c);
    // The name is only shown, in messages and the viewer: kept printable and short.
    camera.name = entry.contains("img_name") && entry["img_name"].is_string()
                      ? printable_file_text(entry["img_name"].get<std::string>(), kMaxCameraNameBytes)
                      : "camera " + std::to_string(i);
    cameras.push_back(camera);
  }
  return cameras;
}

std::vector<Camera> load_cameras(const std::string& path) {
  const std::vector<char> bytes = read_regular_file(path, kMaxCameraFileBytes);
  return parse_cameras(std::string(bytes.begin(), bytes.end()), path);
}

void save_cameras(const std::vector<Camera>& cameras, const std::string& path) {
  json doc = json::array();
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const Camera& cam = cameras[i];
    json rotation = json::array();
    for (int r = 0; r < 3; ++r)  // camera-to-world = transpose of our world-to-camera
      rotation.push_back({cam.rotation[r], cam.rotation[3 + r], cam.rotation[6 + r]});
    doc.push_back({{"id", i},
                   {"img_name", cam.name},
                   {"width", cam.width},
                   {"height", cam.height},
                   {"position", {cam.position[0], cam.position[1], cam.position[2]}},
                   {"rotation", rotation},
                   {"fx", cam.fx},
                   {"fy", cam.fy}});
  }
  write_file_atomically(path, doc.dump(1) + "\n");
}

}  // namespace flashgs
